#pragma once
/// @file
/// `HapticLoop`: runs a `HapticRenderer` on its own thread at a fixed rate (default 1 kHz) and
/// records the measured periods (into storage reserved before the thread starts) so their
/// percentiles can be reported. The loop sleeps until each deadline (it does not spin: the machine
/// is shared); after an overrun it resynchronises instead of bursting to catch up.

#include <atomic>
#include <thread>
#include <vector>

#include "gipsi/haptics/haptic_tick.h"

namespace gipsi {

/// Period statistics of a finished run [s]. Plain struct.
struct HapticLoopStats {
  std::int64_t ticks = 0;
  double target_period = 0;
  double p50 = 0, p99 = 0, p999 = 0, max = 0;  ///< measured periods
  /// Percentiles of |period − target|.
  double error_p50 = 0, error_p99 = 0, error_p999 = 0;
  double mean_tick_cost = 0;  ///< wall time inside HapticRenderer::Run per tick
};

/// Not copyable or movable (its thread refers to it).
class HapticLoop {
 public:
  /// `rate` in Hz (> 0, up to 10 kHz); records up to `max_records` periods.
  HapticLoop(HapticRenderer& tick, double rate = 1000, std::size_t max_records = 1 << 20);
  HapticLoop(const HapticLoop&) = delete;
  HapticLoop& operator=(const HapticLoop&) = delete;
  ~HapticLoop();

  /// Starts the thread (once).
  void Start();
  /// Stops and joins the thread; idempotent.
  void Stop();
  /// Statistics of the periods recorded so far (call after Stop).
  [[nodiscard]] HapticLoopStats Stats() const;

 private:
  void Run();
  HapticRenderer& tick_;
  double period_;
  std::vector<double> periods_;
  std::size_t recorded_ = 0;
  double cost_ = 0;
  std::int64_t ticks_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace gipsi
