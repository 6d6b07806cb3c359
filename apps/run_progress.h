#pragma once
/// @file
/// The run's progress report of `gipsi run` (and `gipsi view --at-end`): a bar with the
/// estimated wall time left on a terminal, a plain line at every 10 % otherwise. Header-only so
/// the tests drive it with their own clock (tests/apps/run_progress_test.cc).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>

#include <fmt/format.h>

namespace gipsi::cli {

/// "1m05s" / "12s" / "3h02m" for a number of wall seconds (negative counts as 0).
inline std::string Duration(double seconds) {
  const auto s = static_cast<std::int64_t>(std::llround(std::max(0.0, seconds)));
  if (s >= 3600) return fmt::format("{}h{:02d}m", s / 3600, (s % 3600) / 60);
  if (s >= 60) return fmt::format("{}m{:02d}s", s / 60, s % 60);
  return fmt::format("{}s", s);
}

/// Wall-clock seconds since an arbitrary origin (steady).
inline double SteadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Progress of a run, written to `out`. On a terminal (`tty`): a bar rewritten in place at most
/// 10 times a second. Otherwise a plain line at every 10 % of the run. Both show the estimated
/// wall time left, "ETA", once the run has taken 0.5 s: the pace since the first report
/// (simulated seconds per wall second, so a resumed run is paced from where it resumed) applied
/// to the simulated time left. Nothing when `quiet`. Not thread-safe (the run's thread calls it).
class RunProgress {
 public:
  RunProgress(bool quiet, bool tty, std::FILE* out,
              std::function<double()> wall_seconds = SteadySeconds)
      : quiet_(quiet), tty_(tty), out_(out), wall_(std::move(wall_seconds)) {}

  /// Reports simulated time `t` of a run that ends at `end`.
  void Update(double t, double end) {
    if (quiet_ || end <= 0) return;
    const double fraction = std::min(1.0, t / end);
    const double now = wall_();
    if (!started_) {  // the first report's time and wall clock: the pace is measured from here
      started_ = true;
      t0_ = t;
      wall0_ = now;
    }
    const double elapsed = now - wall0_;
    const std::string eta = t > t0_ && elapsed > 0.5
                                ? fmt::format(", ETA {}", Duration(elapsed * (end - t) / (t - t0_)))
                                : std::string();
    if (tty_) {
      if (drawn_once_ && now - last_ < 0.1 && fraction < 1.0) return;
      drawn_once_ = true;
      last_ = now;
      const int width = 30, filled = static_cast<int>(fraction * width);
      std::fprintf(out_, "\r[%s%s] %5.1f%%  t = %.4g / %.4g s%s\033[K",
                   std::string(filled, '#').c_str(), std::string(width - filled, ' ').c_str(),
                   100 * fraction, t, end, eta.c_str());
      std::fflush(out_);
      dirty_ = true;
    } else {
      const int decile = static_cast<int>(fraction * 10 + 1e-9);
      if (decile <= last_decile_) return;
      last_decile_ = decile;
      std::fprintf(out_, "progress: %3d%%  t = %.6g s%s\n", decile * 10, t,
                   decile < 10 ? eta.c_str() : "");
    }
  }

  /// Ends the bar's line (on a terminal).
  void Done() {
    if (dirty_) std::fprintf(out_, "\n");
    dirty_ = false;
  }

 private:
  bool quiet_, tty_;
  std::FILE* out_;
  std::function<double()> wall_;
  bool dirty_ = false, started_ = false, drawn_once_ = false;
  int last_decile_ = 0;
  double t0_ = 0, wall0_ = 0, last_ = 0;
};

}  // namespace gipsi::cli
