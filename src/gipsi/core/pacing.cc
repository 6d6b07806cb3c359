#include "gipsi/core/pacing.h"

#include <algorithm>
#include <chrono>
#include <thread>

namespace gipsi {

void WaitForWallClock(const WallClockPaced& clock, double sim_time, double until, StopToken stop) {
  constexpr double kSlice = 0.01;  // [s]: a stop request waits at most this long
  for (;;) {
    const double ahead = until - clock.WallClockTime(sim_time);
    if (!(ahead > 0) || stop.stop_requested()) return;
    std::this_thread::sleep_for(std::chrono::duration<double>(std::min(ahead, kSlice)));
  }
}

}  // namespace gipsi
