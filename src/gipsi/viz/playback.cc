#include "gipsi/viz/playback.h"

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi::viz {

AtEnd ParseAtEnd(std::string_view text, std::string_view option) {
  if (text == "pause") return AtEnd::kPause;
  if (text == "loop") return AtEnd::kLoop;
  if (text == "continue") return AtEnd::kContinue;
  ThrowInputError("command line", option,
                  fmt::format("expected pause, loop or continue, got '{}'", text));
}

PlayStep NextPlayStep(double time, double end_time, double macro_dt, AtEnd at_end,
                      bool running_until) {
  if (running_until || time < end_time - 1e-6 * macro_dt) return PlayStep::kStep;
  switch (at_end) {
    case AtEnd::kPause:
      return PlayStep::kPause;
    case AtEnd::kLoop:
      return PlayStep::kRestart;
    case AtEnd::kContinue:
      break;
  }
  return PlayStep::kStep;
}

}  // namespace gipsi::viz
