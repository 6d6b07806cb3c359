#pragma once
/// @file
/// `HapticLoop`: runs a `HapticRenderer` on its own thread at a fixed rate (default 1 kHz) and
/// records the measured periods (into storage reserved before the thread starts) so their
/// percentiles can be reported. The loop sleeps until each deadline (it does not spin: the machine
/// is shared); after an overrun it resynchronises instead of bursting to catch up. Optionally the
/// thread runs under SCHED_FIFO and is pinned to a CPU (`HapticRealtime`); when the process may
/// not do that, the loop logs one warning and runs at normal priority. In both cases the
/// thread's timer slack is set to 1 ns (Linux's default of 50 µs for normal threads would be
/// the whole jitter budget).

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/haptics/haptic_tick.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Real-time scheduling of the loop thread. Plain struct with defaults.
struct HapticRealtime {
  bool fifo = false;  ///< request SCHED_FIFO (needs root or CAP_SYS_NICE)
  int priority = 80;  ///< SCHED_FIFO priority, 1–99
  int cpu = -1;       ///< pin the thread to this CPU (−1: no pinning)
  /// s, in [0, period): sleep until this long before each tick's deadline, then spin on the
  /// clock, so a late timer wake-up within it does not delay the tick; costs that share of a
  /// core. 0: sleep only.
  double spin = 0;
};

/// Period statistics of a finished run [s]. Plain struct.
struct HapticLoopStats {
  std::int64_t ticks = 0;
  double target_period = 0;
  double p50 = 0, p99 = 0, p999 = 0, max = 0;  ///< measured periods
  /// Percentiles of |period − target|.
  double error_p50 = 0, error_p99 = 0, error_p999 = 0;
  double mean_tick_cost = 0;  ///< wall time inside HapticRenderer::Run per tick
  bool fifo = false;          ///< the thread ran under SCHED_FIFO
  bool pinned = false;        ///< the thread was pinned to the requested CPU
};

/// Not copyable or movable (its thread refers to it).
class HapticLoop {
 public:
  /// `rate` in Hz (> 0, up to 10 kHz); records up to `max_records` periods; `realtime`: see
  /// HapticRealtime (priority must be in 1–99).
  HapticLoop(HapticRenderer& tick, double rate = 1000, std::size_t max_records = 1 << 20,
             const HapticRealtime& realtime = {});
  HapticLoop(const HapticLoop&) = delete;
  HapticLoop& operator=(const HapticLoop&) = delete;
  ~HapticLoop();

  /// Starts the thread (once) and waits until it has applied the scheduling requested; logs
  /// one warning for each part of it (SCHED_FIFO, CPU pinning) that was not permitted.
  void Start();
  /// Stops and joins the thread; idempotent.
  void Stop();
  /// Statistics of the periods recorded so far (call after Stop).
  [[nodiscard]] HapticLoopStats Stats() const;
  /// Whether the thread has been started and not stopped yet.
  [[nodiscard]] bool running() const { return thread_.joinable(); }
  /// Seconds on the loop's clock: wall-clock time since Start, the time the renderer is ticked
  /// with. Safe from any thread once Start has returned (0 before the first Start).
  [[nodiscard]] double Elapsed() const;

 private:
  void Run();
  void ApplyScheduling();
  HapticRenderer& tick_;
  double period_;
  HapticRealtime realtime_;
  int fifo_error_ = 0, pin_error_ = 0;  // errno of the failed requests (set before ready_)
  std::atomic<bool> ready_{false};
  std::chrono::steady_clock::time_point start_{};  // set before the thread starts
  std::vector<double> periods_;
  std::size_t recorded_ = 0;
  double cost_ = 0;
  std::int64_t ticks_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
