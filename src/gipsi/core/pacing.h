#pragma once
/// @file
/// Real-time pacing. An object whose time runs on the wall clock (a haptic device ticking in a
/// real-time loop) implements `WallClockPaced`; the coordinator then never steps it past the
/// wall clock: before each of its sub-steps it waits, if it must, until the wall clock reaches
/// the sub-step's end. The pacing is the kernel's alone (one rule for every object, in
/// `Coordinator::MacroStep`): an object does not sleep in its own step, and a stop request ends
/// the wait at once.

#include "gipsi/base/export.h"
#include "gipsi/base/stop_token.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The capability of an object paced by the wall clock.
class WallClockPaced {
 public:
  virtual ~WallClockPaced() = default;
  /// The simulation time the wall clock shows now [s], for an object at simulation time
  /// `sim_time`; +infinity (nothing to wait for) while the object does not run on the wall
  /// clock.
  [[nodiscard]] virtual double WallClockTime(double sim_time) const = 0;
};

/// Waits until `clock.WallClockTime(sim_time)` reaches `until` [s], sleeping in slices of at
/// most 10 ms; returns early when `stop` is requested.
void WaitForWallClock(const WallClockPaced& clock, double sim_time, double until, StopToken stop);

}  // namespace gipsi
GIPSI_EXPORT_END
