#include "gipsi/viz/display_manager.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/display_publisher.h"

namespace gipsi::viz {
namespace {

using ::testing::HasSubstr;

/// A unit-cube FEM block (2x2x2 cells, 5 tets each), optionally with an embedded display sheet
/// across its middle (z = 0.5).
Scene LoadBlock(bool embedded_sheet, TypeRegistry& registry) {
  RegisterBuiltins(registry);
  const std::string display =
      embedded_sheet ? R"(, "display": {"mesh": "sheet", "mapping": "barycentric"})" : "";
  const std::string text = R"({
    "meshes": {
      "block": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [2, 2, 2]},
      "sheet": {"generate": "sheet", "origin": [0.1, 0.1, 0.5], "u": [0.8, 0, 0],
                "v": [0, 0.8, 0], "cells": [4, 4]}
    },
    "objects": {"block": {"type": "FemSolid", "domain": "block", "dt": 0.01, "density": 1000,
      "material": {"law": "Corotational", "youngs_modulus": 1e5, "poisson_ratio": 0.3},
      "integrator": "BackwardEuler")" +
                           display + R"(}},
    "schedule": {"end": 0.01}
  })";
  return LoadSceneFromString(text, "block.json", ".", registry);
}

TEST(DisplayManager, SolidSurfaceIsTheOutwardBoundary) {
  TypeRegistry registry;
  Scene scene = LoadBlock(false, registry);
  const SimObject& block = scene.kernel->FindObject("block");
  DisplayManager manager(block, ColorSpec{});
  SurfaceBuffers out;
  manager.Fill(out);
  const BoundarySurface& boundary = block.boundary();
  ASSERT_EQ(out.num_vertices(), std::size_t(boundary.num_vertices()));
  ASSERT_EQ(out.num_triangles(), std::size_t(boundary.num_triangles()));
  EXPECT_TRUE(out.values.empty());
  for (std::size_t v = 0; v < out.num_vertices(); ++v) {
    const Vec3 node = block.domain().nodes.col(boundary.vertex_to_node[v]);
    const Vec3 x(out.positions[3 * v], out.positions[3 * v + 1], out.positions[3 * v + 2]);
    EXPECT_LT((x - node).norm(), 1e-6);  // float copy of a double in [0, 1]
    // On a convex block every area-weighted vertex normal points away from the centre.
    const Vec3 n(out.normals[3 * v], out.normals[3 * v + 1], out.normals[3 * v + 2]);
    EXPECT_NEAR(n.norm(), 1.0, 1e-6);
    EXPECT_GT(n.dot(node - Vec3(0.5, 0.5, 0.5)), 0.0);
    EXPECT_EQ(out.colors[3 * v], 0.80f);
  }
}

TEST(DisplayManager, ColoursByANodeFieldComponentThroughTheMap) {
  TypeRegistry registry;
  Scene scene = LoadBlock(false, registry);
  ColorSpec spec;
  spec.field = "position";
  spec.component = 0;
  spec.color_map = "grey";
  DisplayManager manager(scene.kernel->FindObject("block"), spec);
  SurfaceBuffers out;
  manager.Fill(out);
  EXPECT_EQ(out.field, "position x");
  EXPECT_EQ(out.units, "m");
  EXPECT_EQ(out.range_lo, 0.0);  // automatic range: the block spans x in [0, 1]
  EXPECT_EQ(out.range_hi, 1.0);
  for (std::size_t v = 0; v < out.num_vertices(); ++v) {
    EXPECT_EQ(out.values[v], out.positions[3 * v]);
    EXPECT_NEAR(out.colors[3 * v], out.positions[3 * v], 1e-6);  // grey: colour = (x-lo)/(hi-lo)
  }
}

TEST(DisplayManager, FixedRangeClampsColours) {
  TypeRegistry registry;
  Scene scene = LoadBlock(false, registry);
  ColorSpec spec;
  spec.field = "position";
  spec.component = 2;
  spec.color_map = "grey";
  spec.range = std::pair{0.25, 0.75};
  DisplayManager manager(scene.kernel->FindObject("block"), spec);
  SurfaceBuffers out;
  manager.Fill(out);
  EXPECT_EQ(out.range_lo, 0.25);
  for (std::size_t v = 0; v < out.num_vertices(); ++v) {
    const double z = out.positions[3 * v + 2];
    EXPECT_NEAR(out.colors[3 * v], std::clamp((z - 0.25) / 0.5, 0.0, 1.0), 1e-6);
  }
}

TEST(DisplayManager, AveragesElementFieldsToNodes) {
  TypeRegistry registry;
  Scene scene = LoadBlock(false, registry);
  SimObject& block = scene.kernel->FindObject("block");
  const FieldId tension = block.FindField("active_tension");
  const Index num_tets = block.domain().num_tets();
  Eigen::MatrixXd values(1, num_tets);
  for (Index e = 0; e < num_tets; ++e) values(0, e) = double(e * e % 17);
  block.WriteField(tension, values);
  ColorSpec spec;
  spec.field = "active_tension";
  DisplayManager manager(block, spec);
  SurfaceBuffers out;
  manager.Fill(out);
  // Brute force: the mean over every tet that uses the node.
  const Tets& tets = block.domain().tets;
  for (std::size_t v = 0; v < out.num_vertices(); ++v) {
    const int node = block.boundary().vertex_to_node[v];
    double sum = 0;
    int count = 0;
    for (Index e = 0; e < num_tets; ++e)
      if ((tets.col(e).array() == node).any()) sum += values(0, e), ++count;
    ASSERT_GT(count, 0);
    EXPECT_NEAR(out.values[v], sum / count, 1e-5 * (1 + sum / count));  // float storage
  }
}

TEST(DisplayManager, EmbeddedDisplaySurfaceInterpolatesNodeFields) {
  TypeRegistry registry;
  Scene scene = LoadBlock(true, registry);
  const SimObject& block = scene.kernel->FindObject("block");
  ColorSpec spec;
  spec.field = "position";  // x is linear in space: barycentric interpolation reproduces it
  spec.component = 0;
  DisplayManager manager(block, spec);
  SurfaceBuffers out;
  manager.Fill(out);
  ASSERT_EQ(out.num_vertices(), 25u);  // the 5 x 5 sheet, not the block's boundary
  ASSERT_EQ(out.num_triangles(), 32u);
  for (std::size_t v = 0; v < out.num_vertices(); ++v) {
    const Vec3 x(out.positions[3 * v], out.positions[3 * v + 1], out.positions[3 * v + 2]);
    EXPECT_NEAR(x.z(), 0.5, 1e-6);
    EXPECT_NEAR(out.values[v], x.x(), 1e-6);  // float storage of values in [0, 1]
  }
}

TEST(DisplayManager, RejectsFieldsItCannotDraw) {
  TypeRegistry registry;
  Scene scene = LoadBlock(true, registry);
  const SimObject& block = scene.kernel->FindObject("block");
  auto message = [&](std::string field, int component = -1,
                     std::string map = "viridis") -> std::string {
    ColorSpec spec;
    spec.field = std::move(field);
    spec.component = component;
    spec.color_map = std::move(map);
    try {
      DisplayManager manager(block, spec);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_THAT(message("stress"), HasSubstr("object 'block'"));
  EXPECT_THAT(message("kinetic_energy"),
              HasSubstr("object 'block': display colour: field 'kinetic_energy' lives on "
                        "globals; colour by a node, element or boundary-vertex field"));
  EXPECT_THAT(message("reaction_force"),
              HasSubstr("lives on boundary vertices, but the object is drawn with an embedded "
                        "display surface"));
  EXPECT_THAT(message("active_tension", 1),
              HasSubstr("field 'active_tension' has 1 component(s); component 1 does not exist"));
  EXPECT_THAT(message("position", -1, "jet"), HasSubstr("unknown colour map 'jet'"));
}

TEST(ParseColorSpec, ReadsEveryKeyAndNamesThePathOfBadValues) {
  auto doc = JsonDocument::Parse(
      R"({"a": {"field": "displacement", "component": "z", "map": "cool-warm", "range": [-1, 1]},
          "b": {"field": "x", "range": [1, 0]},
          "c": {"map": "virdis"}, "d": {"colour": [1, 0, 0]}})",
      "s.json");
  const ColorSpec a = ParseColorSpec(doc.root().At("a"));
  EXPECT_EQ(a.field, "displacement");
  EXPECT_EQ(a.component, 2);
  EXPECT_EQ(a.color_map, "cool-warm");
  EXPECT_EQ(a.range, std::pair(-1.0, 1.0));
  auto message = [&](const char* key) -> std::string {
    try {
      (void)ParseColorSpec(doc.root().At(key));
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_THAT(message("b"), HasSubstr("s.json: b.range: expected [lo, hi] with lo < hi"));
  EXPECT_THAT(message("c"), HasSubstr("s.json: c.map: unknown colour map 'virdis'"));
  EXPECT_THAT(message("d"), HasSubstr("s.json: d"));
  EXPECT_THAT(message("d"), HasSubstr("colour"));
}

TEST(ParseColorOption, SplitsObjectFieldAndComponent) {
  auto [object, spec] = ParseColorOption("liver:displacement.z", "cool-warm", std::nullopt, "--c");
  EXPECT_EQ(object, "liver");
  EXPECT_EQ(spec.field, "displacement");
  EXPECT_EQ(spec.component, 2);
  EXPECT_EQ(spec.color_map, "cool-warm");
  std::tie(object, spec) =
      ParseColorOption("heart.muscle:von_mises_stress", "viridis", std::pair{0.0, 5e3}, "--c");
  EXPECT_EQ(object, "heart.muscle");
  EXPECT_EQ(spec.field, "von_mises_stress");
  EXPECT_EQ(spec.component, -1);
  EXPECT_EQ(spec.range, std::pair(0.0, 5e3));
  for (const char* bad : {"liver", ":x", "liver:", "liver:displacement.w"}) {
    try {
      (void)ParseColorOption(bad, "viridis", std::nullopt, "--c");
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("command line: --c: ")) << bad;
    }
  }
}

TEST(DisplayPublisher, PublishesAFrameAfterEveryMacroStep) {
  TypeRegistry registry;
  Scene scene = LoadBlock(false, registry);
  LatestValue<FrameBuffers> frames;
  scene.kernel->AddObserver(
      std::make_unique<DisplayPublisher>(SceneDisplay(*scene.kernel, {}), frames));
  ASSERT_TRUE(scene.kernel->Run(0.03).ok());
  ASSERT_TRUE(frames.Fetch());
  // Observed at t = 0 and after each of the 3 macro steps: the newest is frame 3 at 0.03 s.
  EXPECT_EQ(frames.front().frame, 3);
  EXPECT_DOUBLE_EQ(frames.front().time, 0.03);
  ASSERT_EQ(frames.front().surfaces.size(), 1u);
  EXPECT_EQ(frames.front().surfaces[0].object, "block");
}

}  // namespace
}  // namespace gipsi::viz
