// Haptic rendering: cost of one tick (device read, model fetch, plane rendering, safety stage,
// command), and the haptic loop's period percentiles over 10 s at 1 kHz while a physics thread
// steps a 10x10x10 mass-spring block and publishes a local model after every step.

#include <benchmark/benchmark.h>

#include <atomic>
#include <thread>

#include "gipsi/geometry/generators.h"
#include "gipsi/haptics/haptic_loop.h"
#include "gipsi/haptics/virtual_device.h"
#include "gipsi/models/mass_spring/mass_spring.h"

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

void BM_HapticLoopUnderPhysics(benchmark::State& state) {
  const double seconds = static_cast<double>(state.range(0));
  for (auto _ : state) {
    VirtualDevice device({{0.0, Vec3(0, 0, 0.001), 0}, {seconds, Vec3(0, 0, -0.002), 0}});
    LatestValue<PlaneLocalModel> models;
    HapticTick tick(device, DeviceWorkspace{}, models, ForceSafetyParams{});
    std::atomic<bool> stop{false};
    const auto start = std::chrono::steady_clock::now();
    std::thread physics([&] {
      MassSpringParams params;
      MassSpring block(
          "block",
          std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3(0.1, 0.1, 0.1), {10, 10, 10})),
          params, std::make_unique<SymplecticEuler>());
      while (!stop.load()) {
        (void)block.Step(1e-4);
        PlaneLocalModel& m = models.back();
        m.stiffness = 500;
        m.active = true;
        m.published_at =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        models.Publish();
      }
    });
    HapticLoop loop(tick, 1000);
    loop.Start();
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    loop.Stop();
    stop.store(true);
    physics.join();
    const HapticLoopStats s = loop.Stats();
    state.counters["ticks"] = static_cast<double>(s.ticks);
    state.counters["period_p50_us"] = 1e6 * s.p50;
    state.counters["period_p99_us"] = 1e6 * s.p99;
    state.counters["period_p999_us"] = 1e6 * s.p999;
    state.counters["error_p99_us"] = 1e6 * s.error_p99;
    state.counters["tick_cost_us"] = 1e6 * s.mean_tick_cost;
  }
}
BENCHMARK(BM_HapticLoopUnderPhysics)->Arg(10)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
}  // namespace gipsi
