#include "gipsi/haptics/realtime_haptics.h"

#include <fmt/format.h>

#include "gipsi/base/log.h"

namespace gipsi {

std::vector<RealtimeProbe> RealtimeProbes(Kernel& kernel) {
  std::vector<RealtimeProbe> probes;
  Coordinator& coordinator = kernel.coordinator();
  for (std::size_t i = 0; i < coordinator.num_objects(); ++i) {
    SimObject& object = coordinator.object(i);
    if (auto* endpoint = dynamic_cast<HapticEndpoint*>(&object))
      if (endpoint->realtime()) probes.push_back({&object, endpoint});
  }
  return probes;
}

std::string DescribeLoopStats(const HapticLoopStats& s) {
  return fmt::format(
      "{} ticks at {:.6g} Hz; period p50 {:.1f} us, p99 {:.1f} us, p99.9 {:.1f} us, max {:.1f} "
      "us; |period error| p99 {:.1f} us; mean tick {:.2f} us; {}{}",
      s.ticks, s.target_period > 0 ? 1 / s.target_period : 0.0, 1e6 * s.p50, 1e6 * s.p99,
      1e6 * s.p999, 1e6 * s.max, 1e6 * s.error_p99, 1e6 * s.mean_tick_cost,
      s.fifo ? "SCHED_FIFO" : "normal priority", s.pinned ? ", pinned" : "");
}

RealtimeHaptics::RealtimeHaptics(Kernel& kernel)
    : kernel_(kernel), probes_(RealtimeProbes(kernel)) {}

RealtimeHaptics::~RealtimeHaptics() {
  try {
    (void)Stop();
  } catch (...) {  // logging failed; the loops are stopped by then or by their probes
  }
}

void RealtimeHaptics::Start() {
  if (running_) return;
  running_ = true;
  for (const RealtimeProbe& probe : probes_)
    if (!probe.endpoint->loop_running()) probe.endpoint->StartLoop(kernel_.time());
}

std::vector<std::pair<std::string, HapticLoopStats>> RealtimeHaptics::Stop() {
  std::vector<std::pair<std::string, HapticLoopStats>> out;
  if (!running_) return out;
  running_ = false;
  for (const RealtimeProbe& probe : probes_) {
    const HapticLoopStats stats = probe.endpoint->StopLoop();
    if (stats.ticks == 0) continue;
    const std::string& name = probe.object->name();
    Log().info("haptic loop of '{}': {}", name, DescribeLoopStats(stats));
    out.emplace_back(name, stats);
  }
  return out;
}

}  // namespace gipsi
