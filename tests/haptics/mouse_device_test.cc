// The mouse-driven haptic device: the mapping from the viewer's pick ray to the tool (exact
// geometry), the wait-free hand-over of poses from a GUI thread to the haptic side (never a torn
// or older pose, no allocation on the reading side) and of forces back, and its scene keys.

#include <atomic>
#include <thread>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/haptics/haptic_probe.h"
#include "gipsi/haptics/mouse_device.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "haptics/no_allocation_guard.h"
#include "io/scene_test_util.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;
using testing::NoAllocationGuard;

TEST(RayPlanePoint, MeetsThePlaneAheadOfTheRayOnly) {
  // From (0, 0, 10) along (1, 0, −1): the plane z = 0 is met at (10, 0, 0).
  const auto hit = RayPlanePoint(Vec3(0, 0, 10), Vec3(1, 0, -1), Vec3(3, 4, 0), Vec3(0, 0, 2));
  ASSERT_TRUE(hit);
  EXPECT_LT((*hit - Vec3(10, 0, 0)).norm(), 1e-12);  // a few roundings of O(10)
  EXPECT_FALSE(RayPlanePoint(Vec3(0, 0, 10), Vec3(1, 0, 0), Vec3::Zero(), Vec3::UnitZ()));
  EXPECT_FALSE(RayPlanePoint(Vec3(0, 0, 10), Vec3(0, 0, 1), Vec3::Zero(), Vec3::UnitZ()));
  EXPECT_FALSE(RayPlanePoint(Vec3(0, 0, 10), Vec3::Zero(), Vec3::Zero(), Vec3::UnitZ()));
}

TEST(MouseDevice, DragsInThePlaneFacingTheViewerAndTheWheelSetsTheDepth) {
  MouseDeviceParams params;
  params.start = Vec3(0.01, 0.02, 0.05);
  params.wheel_step = 0.001;
  MouseDevice mouse(params);
  // Headless (nothing moves it) the tool stays at its start pose, and a drag that was never
  // begun does nothing.
  EXPECT_EQ(mouse.Read(0).position, params.start);
  EXPECT_TRUE(mouse.Read(0).connected);
  EXPECT_FALSE(mouse.DragTo(Vec3(0, 0, 1), Vec3(0, 0, -1)));
  EXPECT_EQ(mouse.Read(1).position, params.start);

  // Camera looking down −z: the drag plane is z = 0.05 through the tool; a vertical pick ray
  // through (0.03, −0.01) puts the tool exactly there.
  const Vec3 forward(0, 0, -1);
  mouse.BeginDrag(forward);
  ASSERT_TRUE(mouse.DragTo(Vec3(0.03, -0.01, 1), Vec3(0, 0, -1)));
  // (Exact up to the rounding of 1 − 0.95, a few 1e-17.)
  EXPECT_LT((mouse.Read(2).position - Vec3(0.03, -0.01, 0.05)).norm(), 1e-15);
  // Two wheel notches push the tool 2 mm into the scene, and the drag plane moves along: an
  // oblique ray from (0, 0, 1.048) along (1, 0, −1) meets z = 0.048 at x = 1.
  mouse.Push(forward, 2);
  EXPECT_NEAR(mouse.Read(3).position.z(), 0.048, 1e-15);
  EXPECT_LT((mouse.Read(3).position.head<2>() - Vec3(0.03, -0.01, 0).head<2>()).norm(), 1e-15);
  ASSERT_TRUE(mouse.DragTo(Vec3(0, 0, 1.048), Vec3(1, 0, -1)));
  EXPECT_LT((mouse.Read(4).position - Vec3(1, 0, 0.048)).norm(), 1e-12);
  // A ray parallel to the plane misses it: the tool stays.
  EXPECT_FALSE(mouse.DragTo(Vec3(0, 0, 0), Vec3(1, 0, 0)));
  mouse.EndDrag();
  EXPECT_FALSE(mouse.dragging());
  EXPECT_FALSE(mouse.DragTo(Vec3(0.5, 0, 1), Vec3(0, 0, -1)));
  EXPECT_EQ(mouse.position(), mouse.Read(5).position);
  // Forces go back to the GUI side.
  EXPECT_EQ(mouse.TakeForce(), Vec3::Zero());
  mouse.Command(Vec3(0, 0, 0.25), Vec3::Zero());
  EXPECT_EQ(mouse.TakeForce(), Vec3(0, 0, 0.25));
  EXPECT_THROW(MouseDevice(MouseDeviceParams{Vec3::Zero(), 0.0}), InputError);
}

TEST(MouseDevice, HandsPosesOverWholeAndInOrderWithoutAllocatingOnTheReadingSide) {
  // A GUI thread pushes the tool along x one step at a time (x = 1, 2, ..., N, exact in
  // double); the reading side must only ever see whole poses (y = z = 0, x an integer) that
  // never go back, and the last one in the end.
  MouseDeviceParams params;
  params.wheel_step = 1;
  MouseDevice mouse(params);
  constexpr int kSteps = 200000;
  std::atomic<bool> done{false};
  std::thread gui([&] {
    for (int k = 0; k < kSteps; ++k) mouse.Push(Vec3::UnitX(), 1);
    done.store(true);
  });
  double last = 0;
  bool whole = true, ordered = true;
  {
    NoAllocationGuard guard;
    while (!done.load()) {
      const DevicePose pose = mouse.Read(0);
      whole = whole && pose.position.y() == 0 && pose.position.z() == 0 &&
              pose.position.x() == static_cast<double>(static_cast<long>(pose.position.x()));
      ordered = ordered && pose.position.x() >= last;
      last = pose.position.x();
      mouse.Command(pose.position, Vec3::Zero());
    }
  }
  gui.join();
  EXPECT_TRUE(whole);
  EXPECT_TRUE(ordered);
  EXPECT_EQ(mouse.Read(0).position.x(), kSteps);
}

std::string ProbeScene(const std::string& probe_keys) {
  return R"({
  "meshes": {"box": {"generate": "box", "min": [0,0,0], "max": [0.02,0.02,0.02], "cells": [2,2,2]}},
  "objects": {
    "cube": {"type": "MassSpring", "domain": "box", "dt": 0.0002, "stiffness": 100,
             "boundary_conditions": [{"name": "bottom", "region": {"group": "zmin"}, "fix": true}]},
    "probe": {"type": "HapticProbe", "dt": 0.001, )" +
         probe_keys + R"(}
  },
  "connectors": {"haptics": {"type": "HapticCoupling", "object": "cube", "device": "probe"}},
  "schedule": {"end": 0.05}
})";
}

std::string LoadError(const std::string& text) { return testing::SceneLoadError(text); }

TEST(MouseDeviceScene, HeadlessTheToolStaysAtItsStart) {
  // Synchronous probe, no viewer: the tool rests 5 mm above the cube's top for the whole run.
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(
      ProbeScene(R"("device": {"type": "Mouse", "start": [0.01, 0.01, 0.025]})"), "mouse.json", ".",
      registry);
  auto& probe = dynamic_cast<HapticProbe&>(scene.kernel->FindObject("probe"));
  ASSERT_NE(probe.mouse_device(), nullptr);
  EXPECT_EQ(probe.igtl_device(), nullptr);
  const RunResult run = scene.kernel->Run(0.05);
  ASSERT_TRUE(run.ok()) << run.diagnostic;
  Eigen::MatrixXd position(3, 1), force(3, 1);
  probe.ReadField(probe.FindField("tool_position"), position);
  probe.ReadField(probe.FindField("tool_force"), force);
  EXPECT_EQ(Vec3(position.col(0)), Vec3(0.01, 0.01, 0.025));
  EXPECT_EQ(Vec3(force.col(0)), Vec3::Zero());  // above the surface: no contact
  EXPECT_EQ(probe.num_ticks(), 50);
}

TEST(MouseDeviceScene, BadKeysAreErrorsNamingTheJsonPath) {
  EXPECT_THAT(LoadError(ProbeScene(R"("device": {"type": "Mouse", "strat": [0, 0, 0]})")),
              HasSubstr("objects.probe.device: unknown key 'strat' (did you mean 'start'?)"));
  EXPECT_THAT(LoadError(ProbeScene(R"("device": {"type": "Mouse"})")),
              HasSubstr("objects.probe.device"));
  EXPECT_THAT(LoadError(ProbeScene(R"("device": {"type": "Mouse", "start": [0, 0]})")),
              HasSubstr("objects.probe.device.start"));
  EXPECT_THAT(
      LoadError(ProbeScene(R"("device": {"type": "Mouse", "start": [0, 0, 0], "wheel_step": 0})")),
      HasSubstr("objects.probe.device.wheel_step"));
  EXPECT_THAT(LoadError(ProbeScene(
                  R"("device": {"type": "Mouse", "start": [0, 0, 0]}, "workspace_scale": 2)")),
              HasSubstr("objects.probe.workspace_scale: a Mouse device works in scene "
                        "coordinates: no workspace mapping"));
  EXPECT_THAT(LoadError(ProbeScene(R"("device": {"type": "Phantom"})")),
              HasSubstr("objects.probe.device.type"));
}

}  // namespace
}  // namespace gipsi
