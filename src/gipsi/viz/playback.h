#pragma once
/// @file
/// What an interactive run does when its simulated time reaches the scene's `schedule.end`
/// while playing: pause there (the default), start again from the beginning, or go on.

#include <string_view>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// The viewer's choice at the end of the schedule (`gipsi view --at-end`).
enum class AtEnd {
  kPause,     ///< stop playing at schedule.end (Play then starts again; Step goes on past it)
  kLoop,      ///< reload the scene and play it again from its start
  kContinue,  ///< keep simulating past the end
};

/// "pause", "loop" or "continue"; throws InputError naming `option` otherwise.
AtEnd ParseAtEnd(std::string_view text, std::string_view option);

/// What the simulation thread does next while playing.
enum class PlayStep { kStep, kPause, kRestart };

/// The next action of a playing run at simulated `time` [s] of a schedule ending at `end_time`,
/// with macro steps of `macro_dt`: a step while before the end (within a millionth of a macro
/// step), else as `at_end` says. `running_until` (an explicit "run to time T", e.g. for a
/// screenshot) steps past the end whatever `at_end` says.
PlayStep NextPlayStep(double time, double end_time, double macro_dt, AtEnd at_end,
                      bool running_until);

}  // namespace gipsi::viz
GIPSI_EXPORT_END
