#pragma once
/// @file
/// When an output sampled every so often (VTU frames, probe rows) is next due.

#include <cmath>
#include <limits>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The first time after `t_due` (the current time plus the kernel's tolerance) on the grid
/// `next + k * every`, k = 1, 2, ...: the next sample time of an output sampled every `every`
/// seconds (> 0) whose sample at `next` (<= t_due) has just been taken. Adds `every` one step at
/// a time as long as that takes a few steps (so the sample times, and checkpoints, stay
/// bitwise what they were), and jumps over a long gap in one go; bounded work for any `every`,
/// even one so small that adding it to `next` changes nothing (the time after `t_due` is
/// returned then).
inline double NextSampleTime(double next, double every, double t_due) {
  constexpr int kSteps = 4;
  if (next <= t_due) {
    const double behind = (t_due - next) / every;
    if (behind > kSteps) next += every * std::floor(behind - 1);
  }
  for (int k = 0; next <= t_due; ++k) {
    const double after = next + every;
    if (after <= next || k > kSteps) return std::nextafter(t_due, HUGE_VAL);
    next = after;
  }
  return next;
}

}  // namespace gipsi
GIPSI_EXPORT_END
