// A HapticProbe with "realtime": its renderer ticks in a HapticLoop on its own thread, on the
// wall clock, while the simulation runs; the probe's step only reads the loop's newest outputs.
// The assertions are on physics (force direction, bounds from the coupling stiffness and the
// penetration, agreement with the synchronous path at the same quasi-static hold, the object's
// equilibrium), never on timing; the loop is joined at the end (the test runs under TSan).

#include <atomic>
#include <chrono>
#include <thread>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/haptics/haptic_probe.h"
#include "gipsi/haptics/realtime_haptics.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/fem/fem_local_model.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/solid_material.h"
#include "haptics/no_allocation_guard.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;
using testing::NoAllocationGuard;

// A 2 × 2 × 2 cm FEM block (E = 100 kPa) on a fixed base, no gravity, strongly damped so a
// held tool reaches a quasi-static state well within 0.2 s; the probe holds the tool still
// 2 mm below the centre of the top face (z = 0.02) from the start. The watchdog's staleness
// limit is raised to 10 s: on a loaded machine (or under TSan) the simulation may lag the wall
// clock, and the fade is tested on its own elsewhere (haptics_test.cc, local_model_test.cc).
constexpr double kDepth = 0.002, kCoupling = 200, kMaxForce = 3;

std::string BlockScene(const std::string& realtime) {
  return R"({
  "meshes": {"block": {"generate": "box", "min": [-0.01, -0.01, 0], "max": [0.01, 0.01, 0.02],
                       "cells": [2, 2, 2]}},
  "objects": {
    "block": {"type": "FemSolid", "domain": "block", "dt": 0.01, "density": 1000,
              "material": {"law": "NeoHookean", "youngs_modulus": 1e5, "poisson_ratio": 0.3},
              "damping": {"mass": 20}, "integrator": "BackwardEuler", "gravity": [0, 0, 0],
              "boundary_conditions": [{"name": "base", "region": {"group": "zmin"}, "fix": true}]},
    "probe": {"type": "HapticProbe", "dt": 0.01, "rate": 1000, "coupling_stiffness": 200,
              "max_force": 3, "stale_after": 10, "path": [[0, 0, 0, 0.018]])" +
         realtime + R"(}
  },
  "connectors": {"haptics": {"type": "HapticCoupling", "object": "block", "device": "probe"}},
  "schedule": {"end": 0.2}
})";
}

Scene Load(const std::string& text) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  return LoadSceneFromString(text, "realtime.json", ".", registry);
}

Vec3 ReadVec(SimObject& object, const char* field) {
  Eigen::MatrixXd v(3, 1);
  object.ReadField(object.FindField(field), v);
  return v.col(0);
}

/// The tool force applied to the block (a boundary condition) and the base's reaction, summed.
std::pair<Vec3, Vec3> BlockLoads(SimObject& block) {
  const BoundarySurface& bnd = block.boundary();
  Vec3 tool = Vec3::Zero();
  for (Index j = 0; j < bnd.num_vertices(); ++j) tool += block.boundary_conditions().force(j);
  Points reaction(3, bnd.num_vertices());
  block.ReadField(block.FindField("reaction_force"), reaction);
  return {tool, reaction.rowwise().sum()};
}

TEST(RealtimeHapticProbe, TicksOnItsOwnThreadAndRendersTheSameContactAsTheSynchronousPath) {
  // The synchronous path for reference.
  Scene sync = Load(BlockScene(""));
  ASSERT_TRUE(sync.kernel->Run(0.2).ok());
  auto& sync_probe = dynamic_cast<HapticProbe&>(sync.kernel->FindObject("probe"));
  const Vec3 f_sync = ReadVec(sync_probe, "tool_force");

  // Sleeping until each deadline, and sleeping until 0.2 ms before it and spinning the rest.
  for (const char* realtime : {R"(, "realtime": true)", R"(, "realtime": {"spin": 0.0002})"}) {
    SCOPED_TRACE(realtime);
    Scene scene = Load(BlockScene(realtime));
    auto& probe = dynamic_cast<HapticProbe&>(scene.kernel->FindObject("probe"));
    ASSERT_TRUE(probe.realtime());
    HapticLoopStats stats;
    {
      const auto wall_start = std::chrono::steady_clock::now();
      RealtimeHaptics haptics(*scene.kernel);
      ASSERT_EQ(haptics.probes().size(), 1u);
      haptics.Start();
      EXPECT_TRUE(probe.loop_running());
      const RunResult run = scene.kernel->Run(0.2);
      ASSERT_TRUE(run.ok()) << run.diagnostic;
      // The simulation never runs ahead of the wall clock: the probe's last step sleeps until
      // 0.2 s have passed on the loop's clock, which started after wall_start (a lower bound
      // from sleep_for's guarantee, not a timing measurement).
      EXPECT_GE(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count(),
          0.2);
      const auto loops = haptics.Stop();
      ASSERT_EQ(loops.size(), 1u);
      EXPECT_EQ(loops[0].first, "probe");
      stats = loops[0].second;
    }
    EXPECT_FALSE(probe.loop_running());  // joined
    EXPECT_GT(stats.ticks, 0);
    EXPECT_LE(stats.p50, stats.p99);
    EXPECT_LE(stats.p99, stats.max);
    EXPECT_GT(probe.num_ticks(), 0);
    EXPECT_LE(probe.num_ticks(), stats.ticks);

    // Physics: the tool is held 2 mm inside; the force on it points out of the top face (+z, the
    // contact vertex is the face's centre, whose normal is +z by symmetry) and, through the
    // coupling spring in series with the tissue, is positive and at most k_c · depth = 0.4 N
    // (and below the 3 N limit).
    const Vec3 f = ReadVec(probe, "tool_force");
    std::printf("tool force: real-time %.6f N (%lld ticks), synchronous %.6f N\n", f.z(),
                static_cast<long long>(stats.ticks), f_sync.z());
    EXPECT_GT(f.z(), 0.1 * kCoupling * kDepth);
    EXPECT_LE(f.z(), kCoupling * kDepth * (1 + 1e-12));
    EXPECT_LE(f.norm(), kMaxForce);
    EXPECT_LT(f.head<2>().norm(), 1e-9 * f.z());  // along the normal up to roundoff
    // The same quasi-static contact as the synchronous path: both render the same local model of
    // the same held block; what differs (which sim times the ticks fall on) has decayed. 2 %.
    EXPECT_NEAR(f.z(), f_sync.z(), 0.02 * f_sync.z());
    // The probe's proxy stays on the local surface, above the tool.
    EXPECT_GT(ReadVec(probe, "proxy_position").z(), 0.018);
    // What the loop handed back reached the block as a boundary force (opposite to the force on
    // the tool, up to the safety stage's rate limit, idle at a steady hold), and the block is in
    // equilibrium: the base carries it (no gravity; the momentum rate is small after the
    // damped transient: 2 % of the load).
    const auto [tool_on_block, support] = BlockLoads(scene.kernel->FindObject("block"));
    EXPECT_LT((tool_on_block + f).norm(), 0.02 * f.norm());
    EXPECT_LT((tool_on_block + support).norm(), 0.02 * tool_on_block.norm());
  }
}

TEST(RealtimeHapticProbe, TheLoopTickAllocatesNothingWhileModelsArePublished) {
  // The renderer the loop runs, ticked on this thread (loop stopped) under the allocation
  // guard while another thread builds and publishes local models of the block.
  Scene scene = Load(BlockScene(R"(, "realtime": {"fifo": false, "cpu": -1})"));
  auto& probe = dynamic_cast<HapticProbe&>(scene.kernel->FindObject("probe"));
  auto* coupling = dynamic_cast<HapticCoupling*>(&scene.kernel->coordinator().connector(0));
  ASSERT_NE(coupling, nullptr);
  HapticRenderer* renderer = probe.loop_renderer();
  ASSERT_NE(renderer, nullptr);
  std::atomic<double> now{0};  // models are stamped with the tick's clock: never stale
  coupling->bridge().Publish(0);
  std::atomic<bool> stop{false};
  // At most every 10 ms of the tick clock, as a 100 Hz object would (every hand-over starts a
  // 10 ms blend from the previous force), and none in the last second of ticks (the ticks run
  // faster than real time; the 5 s of ticks stay within the 10 s staleness limit).
  std::thread simulation([&] {
    double last = 0;
    while (!stop.load()) {
      const double t = now.load();
      if (t >= last + 0.01 && t < 4) {
        coupling->bridge().Publish(t);
        last = t;
      } else {
        std::this_thread::yield();
      }
    }
  });
  Vec3 force = Vec3::Zero();
  {
    NoAllocationGuard guard;
    for (int k = 1; k <= 5000; ++k) {
      now.store(k * 1e-3);
      force = renderer->Run(k * 1e-3, 1e-3);
    }
  }
  stop.store(true);
  simulation.join();
  EXPECT_GT(force.z(), 0);
  EXPECT_LE(force.z(), kCoupling * kDepth * (1 + 1e-12));
}

TEST(RealtimeHapticProbe, WithoutItsLoopTheRunStopsWithAClearDiagnostic) {
  Scene scene = Load(BlockScene(R"(, "realtime": true)"));
  const RunResult run = scene.kernel->Run(0.05);
  EXPECT_FALSE(run.ok());
  EXPECT_THAT(run.diagnostic, HasSubstr("'probe'"));
  EXPECT_THAT(run.diagnostic, HasSubstr("haptic loop is not running"));
}

TEST(RealtimeHapticProbe, BadKeysAreErrorsNamingTheJsonPath) {
  auto error = [](const std::string& realtime) -> std::string {
    try {
      (void)Load(BlockScene(", \"realtime\": " + realtime));
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_THAT(error(R"("yes")"),
              HasSubstr("objects.probe.realtime: expected true, false or an object"));
  EXPECT_THAT(error(R"({"fifoo": true})"),
              HasSubstr("objects.probe.realtime: unknown key 'fifoo' (did you mean 'fifo'?)"));
  EXPECT_THAT(error(R"({"priority": 0})"),
              HasSubstr("objects.probe.realtime.priority: expected an integer in 1-99"));
  EXPECT_THAT(error(R"({"cpu": -2})"), HasSubstr("objects.probe.realtime.cpu: expected a CPU"));
  EXPECT_THAT(error(R"({"fifo": 3})"), HasSubstr("objects.probe.realtime.fifo"));
  EXPECT_THAT(error(R"({"spin": 0.001})"),
              HasSubstr("objects.probe.realtime.spin: expected a time in [0, 0.001) s"));
  EXPECT_THAT(error(R"({"spin": -1e-4})"), HasSubstr("objects.probe.realtime.spin"));
  EXPECT_EQ(error("false"), "(no error)");
}

}  // namespace
/// A local-model builder registered from outside the framework (as a plugin would): it
/// delegates to the FEM condensation and counts its builds.
class CountingCondensation final : public LocalModelBuilder {
 public:
  CountingCondensation(FemSolid& fem, int* builds) : inner_(fem), builds_(builds) {}
  SimObject& object() override { return inner_.object(); }
  bool Build(Index vertex, const Vec3& normal, double anchor_force, double period,
             LocalDynamicModel& out) override {
    ++*builds_;
    return inner_.Build(vertex, normal, anchor_force, period, out);
  }

 private:
  FemCondensation inner_;
  int* builds_;
};

// A HapticCoupling finds its object's local model by the object's type in the registry, not by
// knowing the framework's classes: a registry whose "FemSolid" entry is the counting builder
// renders exactly (bit for bit) the built-in condensation's contact, and that builder did the
// building (once per coupling firing, 20 in 0.2 s, and at the start).
TEST(HapticLocalModels, TheCouplingUsesTheModelRegisteredForTheObjectsType) {
  Scene builtin = Load(BlockScene(""));
  ASSERT_TRUE(builtin.kernel->Run(0.2).ok());
  const Vec3 f_builtin = ReadVec(builtin.kernel->FindObject("probe"), "tool_force");

  int builds = 0;
  // FemSolid's own registration registers its local model too; take only its object factory.
  TypeRegistry builtins;
  RegisterFemSolid(builtins);
  const nlohmann::ordered_json type = "FemSolid";
  TypeRegistry registry;
  RegisterIntegrators(registry);
  RegisterSolidLaws(registry);
  registry.objects.Register(
      "FemSolid", builtins.objects.Get("FemSolid", JsonNode(type, "test", "type")), "FemSolid");
  RegisterHaptics(registry);
  LocalModels(registry).Register(
      "FemSolid",
      [&builds](SimObject& object, int) -> std::unique_ptr<LocalModelBuilder> {
        return std::make_unique<CountingCondensation>(dynamic_cast<FemSolid&>(object), &builds);
      },
      "counting condensation");
  Scene scene = LoadSceneFromString(BlockScene(""), "registered.json", ".", registry);
  ASSERT_TRUE(scene.kernel->Run(0.2).ok());
  const Vec3 f = ReadVec(scene.kernel->FindObject("probe"), "tool_force");
  std::printf("tool force %.6f N with the registered builder (%d builds), %.6f N built in\n",
              f.norm(), builds, f_builtin.norm());
  EXPECT_GT(f_builtin.norm(), 0.1);  // in contact
  EXPECT_EQ(f, f_builtin);
  EXPECT_GE(builds, 20);
}

TEST(HapticLocalModels, AnObjectWhoseTypeHasNoneIsAClearError) {
  std::string text = BlockScene("");
  const std::string fem = R"("block": {"type": "FemSolid")";
  text.replace(
      text.find(fem), fem.size(),
      R"("other": {"type": "Circulation", "dt": 0.01, "compartments": {"lv": {"type": "reservoir", "pressure": 0}}},
    "block": {"type": "FemSolid")");
  text.replace(text.find(R"("object": "block")"), 17, R"("object": "other")");
  try {
    (void)Load(text);
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("connectors.haptics.object: object 'other' is a Circulation, which has "
                          "no haptic local model (types with one: FemSolid, MassSpring)"));
  }
}

}  // namespace gipsi
