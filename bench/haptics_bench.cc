// Haptic rendering: cost of one tick against the plane model and against local dynamic models
// (FEM condensation: 3 dofs; mass-spring neighbourhood: up to 20 nodes, 60 dofs), the cost of
// building those models on the simulation side, and the haptic loop's period percentiles over
// 10 s at 1 kHz while a physics thread steps a 10x10x10 mass-spring block and publishes a
// neighbourhood model after every step, at normal priority and under SCHED_FIFO (pinned to the
// last CPU) in the same run.

#include <benchmark/benchmark.h>

#include <atomic>
#include <thread>

#include "gipsi/geometry/generators.h"
#include "gipsi/haptics/haptic_bridge.h"
#include "gipsi/haptics/haptic_loop.h"
#include "gipsi/haptics/virtual_device.h"
#include "gipsi/models/fem/fem_local_model.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/solid_laws.h"
#include "gipsi/models/mass_spring/mass_spring.h"
#include "gipsi/models/mass_spring/mass_spring_local_model.h"

namespace gipsi {
namespace {

void BM_HapticTick(benchmark::State& state) {
  VirtualDevice device({{0.0, Vec3(0, 0, 0.001), 0}, {1.0, Vec3(0, 0, -0.002), 0}});
  LatestValue<PlaneLocalModel> models;
  models.back().stiffness = 500;
  models.back().active = true;
  models.back().published_at = 1e300;
  models.Publish();
  HapticTick tick(device, DeviceWorkspace{}, models, ForceSafetyParams{});
  double t = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(tick.Run(t, 1e-3));
    t += 1e-6;
  }
}
BENCHMARK(BM_HapticTick);

std::unique_ptr<MassSpring> SpringBlock(int cells) {
  MassSpringParams params;
  params.stiffness = 200;
  params.damping = 0.05;
  auto block =
      std::make_unique<MassSpring>("block",
                                   std::make_shared<const Mesh>(MakeTetBox(
                                       Vec3::Zero(), Vec3(0.1, 0.1, 0.1), {cells, cells, cells})),
                                   params, std::make_unique<SymplecticEuler>());
  const BoundarySurface& b = block->boundary();
  for (Index j = 0; j < b.num_vertices(); ++j)
    if (block->domain().nodes(2, b.vertex_to_node[static_cast<std::size_t>(j)]) == 0)
      block->boundary_conditions().Fix(j);
  return block;
}

std::unique_ptr<FemSolid> FemBlock(int cells) {
  FemParams params;
  params.material = std::make_shared<NeoHookeanSolid>(1e4, 0.45);
  params.gravity = Vec3::Zero();
  params.scheme = ImplicitSchemeKind::kStatic;
  auto fem = std::make_unique<FemSolid>(
      "block",
      std::make_shared<const Mesh>(
          MakeTetBox(Vec3::Zero(), Vec3(0.04, 0.04, 0.02), {cells, cells, cells / 2})),
      params);
  const BoundarySurface& b = fem->boundary();
  for (Index j = 0; j < b.num_vertices(); ++j)
    if (fem->domain().nodes(2, b.vertex_to_node[static_cast<std::size_t>(j)]) == 0)
      fem->boundary_conditions().Fix(j);
  return fem;
}

/// One tick of LocalModelTick against a model from `bridge` (device pressing 1 mm in).
void TickAgainst(benchmark::State& state, HapticBridge& bridge, const Vec3& top) {
  VirtualDevice device({{0.0, Vec3(top - Vec3(0, 0, 0.001)), 0}});
  LocalTickParams params;
  params.safety.stale_after = 1e300;
  LocalModelTick tick(device, DeviceWorkspace{}, bridge.models(), nullptr, params);
  double t = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(tick.Run(t, 1e-3));
    t += 1e-6;
  }
  state.counters["dofs"] = tick.model().dofs();
}

void BM_LocalModelTickMassSpring(benchmark::State& state) {
  auto block = SpringBlock(10);
  MassSpringNeighbourhood builder(*block, static_cast<int>(state.range(0)));
  HapticBridge bridge(builder, HapticBridgeParams{});
  bridge.feedback().back().tool = Vec3(0.05, 0.05, 0.1);
  bridge.feedback().Publish();
  bridge.ApplyFeedback();
  bridge.Publish(0);
  TickAgainst(state, bridge, Vec3(0.05, 0.05, 0.1));
}
BENCHMARK(BM_LocalModelTickMassSpring)->Arg(1)->Arg(2);

void BM_LocalModelTickFem(benchmark::State& state) {
  auto fem = FemBlock(8);
  FemCondensation builder(*fem);
  HapticBridge bridge(builder, HapticBridgeParams{});
  bridge.feedback().back().tool = Vec3(0.02, 0.02, 0.02);
  bridge.feedback().Publish();
  bridge.ApplyFeedback();
  bridge.Publish(0);
  TickAgainst(state, bridge, Vec3(0.02, 0.02, 0.02));
}
BENCHMARK(BM_LocalModelTickFem);

void BM_BuildFemCondensation(benchmark::State& state) {
  auto fem = FemBlock(static_cast<int>(state.range(0)));
  FemCondensation builder(*fem);
  LocalDynamicModel model;
  Index top = 0;
  double best = 1e300;
  for (Index j = 0; j < fem->boundary().num_vertices(); ++j) {
    const Vec3 p =
        fem->domain().nodes.col(fem->boundary().vertex_to_node[static_cast<std::size_t>(j)]);
    const double d = (p - Vec3(0.02, 0.02, 0.02)).norm();
    if (d < best) {
      best = d;
      top = j;
    }
  }
  for (auto _ : state) benchmark::DoNotOptimize(builder.Build(top, Vec3::UnitZ(), 0, 1e-3, model));
  state.counters["nodes"] = static_cast<double>(fem->num_nodes());
}
BENCHMARK(BM_BuildFemCondensation)->Arg(8)->Arg(16)->Unit(benchmark::kMillisecond);

void BM_HapticLoopUnderPhysics(benchmark::State& state) {
  const double seconds = static_cast<double>(state.range(0));
  HapticRealtime realtime;
  if (state.range(1) != 0) {
    realtime.fifo = true;
    realtime.cpu = static_cast<int>(std::thread::hardware_concurrency()) - 1;
  }
  if (state.range(1) == 2) realtime.spin = 150e-6;
  for (auto _ : state) {
    auto block = SpringBlock(10);
    MassSpringNeighbourhood builder(*block, 1);
    HapticBridge bridge(builder, HapticBridgeParams{});
    VirtualDevice device(
        {{0.0, Vec3(0.05, 0.05, 0.101), 0}, {seconds, Vec3(0.05, 0.05, 0.098), 0}});
    LocalTickParams params;
    params.safety.stale_after = 1e300;  // the publisher is not real-time; staleness is tested
    LocalModelTick tick(device, DeviceWorkspace{}, bridge.models(), &bridge.feedback(), params);
    std::atomic<bool> stop{false};
    std::atomic<std::int64_t> published{0};
    bridge.feedback().back().tool = Vec3(0.05, 0.05, 0.101);
    bridge.feedback().Publish();
    std::thread physics([&] {
      while (!stop.load()) {
        bridge.ApplyFeedback();
        (void)block->Step(1e-4);
        bridge.Publish(0);
        published.fetch_add(1);
      }
    });
    HapticLoop loop(tick, 1000, 1 << 20, realtime);
    loop.Start();
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    loop.Stop();
    stop.store(true);
    physics.join();
    const HapticLoopStats s = loop.Stats();
    state.counters["ticks"] = static_cast<double>(s.ticks);
    state.counters["models"] = static_cast<double>(published.load());
    state.counters["period_p50_us"] = 1e6 * s.p50;
    state.counters["period_p99_us"] = 1e6 * s.p99;
    state.counters["period_p999_us"] = 1e6 * s.p999;
    state.counters["error_p50_us"] = 1e6 * s.error_p50;
    state.counters["error_p99_us"] = 1e6 * s.error_p99;
    state.counters["error_p999_us"] = 1e6 * s.error_p999;
    state.counters["period_max_us"] = 1e6 * s.max;
    state.counters["fifo"] = s.fifo ? 1 : 0;
    state.counters["tick_cost_us"] = 1e6 * s.mean_tick_cost;
  }
}
// Second argument: 0 normal priority, 1 SCHED_FIFO (priority 80) pinned to the last CPU, 2 the
// same with the last 150 µs before each deadline spun out instead of slept.
BENCHMARK(BM_HapticLoopUnderPhysics)
    ->Args({10, 0})
    ->Args({10, 1})
    ->Args({10, 2})
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace
}  // namespace gipsi
