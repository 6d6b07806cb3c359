#pragma once
/// @file
/// `RealtimeHaptics`: runs the real-time haptic loops of a scene's probes (HapticProbe with
/// "realtime", or any object with the HapticEndpoint capability that is real-time) for the
/// duration of a run. `gipsi run`, `gipsi view` and `gipsi snapshot` hold
/// one around their runs; a program that runs such a scene's kernel itself does the same:
///
///     RealtimeHaptics haptics(*scene.kernel);
///     haptics.Start();
///     RunResult result = scene.kernel->Run(end);
///     haptics.Stop();  // or leave it to the destructor (also on errors and exceptions)
///
/// Stop joins every loop and logs its period percentiles (p50, p99, p99.9, max) at info level.

#include <string>
#include <utility>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/kernel.h"
#include "gipsi/haptics/haptic_endpoint.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A real-time haptic device among a kernel's objects: the object and its capability.
struct RealtimeProbe {
  SimObject* object;
  HapticEndpoint* endpoint;
};

/// The real-time haptic devices (HapticEndpoint::realtime()) among the kernel's objects (top
/// level; in scene order).
std::vector<RealtimeProbe> RealtimeProbes(Kernel& kernel);

/// One line describing a finished loop: ticks, rate, period percentiles and scheduling.
std::string DescribeLoopStats(const HapticLoopStats& stats);

/// Not copyable or movable (holds the probes).
class RealtimeHaptics {
 public:
  /// Finds the kernel's real-time probes (none: Start and Stop do nothing).
  explicit RealtimeHaptics(Kernel& kernel);
  RealtimeHaptics(const RealtimeHaptics&) = delete;
  RealtimeHaptics& operator=(const RealtimeHaptics&) = delete;
  /// Stops the loops (as Stop) if they run.
  ~RealtimeHaptics();

  /// Starts every probe's loop with its haptic clock at the kernel's current time. Idempotent.
  void Start();
  /// Stops and joins the loops; logs and returns (probe name, statistics) for each loop that
  /// ran. Idempotent (a second call returns nothing).
  std::vector<std::pair<std::string, HapticLoopStats>> Stop();
  /// The real-time probes it runs.
  [[nodiscard]] const std::vector<RealtimeProbe>& probes() const { return probes_; }

 private:
  Kernel& kernel_;
  std::vector<RealtimeProbe> probes_;
  bool running_ = false;
};

}  // namespace gipsi
GIPSI_EXPORT_END
