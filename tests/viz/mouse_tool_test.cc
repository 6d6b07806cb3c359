#include "gipsi/viz/mouse_tool.h"

#include <gtest/gtest.h>

#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/display_manager.h"

namespace gipsi::viz {
namespace {

/// A unit-cube block; `fixed` clamps its bottom face (z = 0).
Scene LoadBlock(TypeRegistry& registry) {
  RegisterBuiltins(registry);
  return LoadSceneFromString(R"({
    "meshes": {"block": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [2, 2, 2]}},
    "objects": {"block": {"type": "FemSolid", "domain": "block", "dt": 0.01, "density": 1000,
      "material": {"law": "Corotational", "youngs_modulus": 1e5, "poisson_ratio": 0.3},
      "integrator": "BackwardEuler",
      "boundary_conditions": [{"name": "base", "region": {"group": "zmin"}, "fix": true}]}},
    "schedule": {"end": 1}
  })",
                             "block.json", ".", registry);
}

FrameBuffers Frame(const Kernel& kernel) {
  SceneDisplay display(kernel, {});
  FrameBuffers frame;
  display.Fill(0, frame);
  return frame;
}

TEST(PickSurface, FindsTheFirstFaceAlongTheRay) {
  TypeRegistry registry;
  Scene scene = LoadBlock(registry);
  const FrameBuffers frame = Frame(*scene.kernel);
  // From in front of the face y = 0, straight at it: the hit is on that face, 2 units away.
  auto hit = PickSurface(frame, Vec3(0.3, -2, 0.6), Vec3(0, 1, 0));
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->distance, 2, 1e-12);
  EXPECT_LT((hit->point - Vec3(0.3, 0, 0.6)).norm(), 1e-12);
  // Pointing away, or passing beside the block: nothing.
  EXPECT_FALSE(PickSurface(frame, Vec3(0.3, -2, 0.6), Vec3(0, -1, 0)).has_value());
  EXPECT_FALSE(PickSurface(frame, Vec3(1.5, -2, 0.6), Vec3(0, 1, 0)).has_value());
  // A hidden surface is not picked.
  EXPECT_FALSE(PickSurface(frame, Vec3(0.3, -2, 0.6), Vec3(0, 1, 0), {true}).has_value());
}

TEST(DragTool, PullsTheNearestFreeVertexThroughItsBoundaryCondition) {
  TypeRegistry registry;
  Scene scene = LoadBlock(registry);
  SimObject& block = scene.kernel->FindObject("block");
  DragTool tool;
  ASSERT_TRUE(tool.Grab(block, Vec3(1.02, 1.01, 0.98)));  // next to the corner (1, 1, 1)
  EXPECT_LT((tool.rest() - Vec3(1, 1, 1)).norm(), 1e-12);
  const Vec3 target(1.2, 1.1, 1.3);
  tool.MoveTo(target);
  ASSERT_TRUE(scene.kernel->Run(0.02).ok());
  // A prescribed displacement: the vertex is exactly where the mouse put it.
  const int node = block.boundary().vertex_to_node[std::size_t(tool.vertex())];
  EXPECT_LT((block.domain_positions().col(node) - target).norm(), 1e-9);
  const Index grabbed = tool.vertex();
  tool.Release();
  EXPECT_FALSE(tool.active());
  EXPECT_EQ(block.boundary_conditions().kind(grabbed, 0), ConstraintKind::kFree);
}

TEST(DragTool, NeverGrabsAVertexTheSceneHolds) {
  TypeRegistry registry;
  Scene scene = LoadBlock(registry);
  SimObject& block = scene.kernel->FindObject("block");
  DragTool tool;
  ASSERT_TRUE(tool.Grab(block, Vec3(0, 0, 0)));  // a clamped corner: the nearest free one
  EXPECT_GT(tool.rest().z(), 0.4);               // is off the clamped base (z = 0)
  const Index v = tool.vertex();
  tool.Release();
  EXPECT_EQ(block.boundary_conditions().kind(v, 2), ConstraintKind::kFree);
  // The base stays fixed after the tool lets go of its neighbour.
  for (Index u = 0; u < block.boundary().num_vertices(); ++u) {
    const int node = block.boundary().vertex_to_node[std::size_t(u)];
    if (block.domain().nodes(2, node) == 0) {
      EXPECT_EQ(block.boundary_conditions().kind(u, 2), ConstraintKind::kDisplacement);
    }
  }
}

}  // namespace
}  // namespace gipsi::viz
