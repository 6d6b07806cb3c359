#include "gipsi/viz/playback.h"

#include <gtest/gtest.h>

#include "gipsi/base/error.h"

namespace gipsi::viz {
namespace {

TEST(Playback, PausesAtTheEndOfTheScheduleByDefault) {
  // Before, the viewer played on past schedule.end ("t = 9.7470 / 1 s").
  EXPECT_EQ(NextPlayStep(0.999, 1.0, 0.001, AtEnd::kPause, false), PlayStep::kStep);
  EXPECT_EQ(NextPlayStep(1.0 - 1e-12, 1.0, 0.001, AtEnd::kPause, false), PlayStep::kPause);
  EXPECT_EQ(NextPlayStep(1.0, 1.0, 0.001, AtEnd::kPause, false), PlayStep::kPause);
  EXPECT_EQ(NextPlayStep(1.0, 1.0, 0.001, AtEnd::kLoop, false), PlayStep::kRestart);
  EXPECT_EQ(NextPlayStep(1.0, 1.0, 0.001, AtEnd::kContinue, false), PlayStep::kStep);
  // An explicit "run to T" (a screenshot's time) goes past the end.
  EXPECT_EQ(NextPlayStep(1.0, 1.0, 0.001, AtEnd::kPause, true), PlayStep::kStep);
}

TEST(Playback, ParsesTheAtEndOption) {
  EXPECT_EQ(ParseAtEnd("pause", "--at-end"), AtEnd::kPause);
  EXPECT_EQ(ParseAtEnd("loop", "--at-end"), AtEnd::kLoop);
  EXPECT_EQ(ParseAtEnd("continue", "--at-end"), AtEnd::kContinue);
  try {
    (void)ParseAtEnd("stop", "--at-end");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "command line: --at-end: expected pause, loop or continue, got 'stop'");
  }
}

}  // namespace
}  // namespace gipsi::viz
