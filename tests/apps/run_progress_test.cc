// The run's progress report (apps/run_progress.h) driven by a test clock: the ETA is the pace
// since the first report applied to the simulated time left, shown once the run has taken
// 0.5 s, also for a run resumed halfway; the plain report writes one line per 10 %.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "run_progress.h"  // apps/ (its include path is set for this file alone)

namespace gipsi::cli {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

/// What `report` wrote to a memory stream.
class Captured {
 public:
  Captured() : file_(open_memstream(&data_, &size_)) {}
  Captured(const Captured&) = delete;
  Captured& operator=(const Captured&) = delete;
  ~Captured() {
    std::fclose(file_);
    std::free(data_);
  }
  std::FILE* file() { return file_; }
  std::string text() {
    std::fflush(file_);
    return std::string(data_, size_);
  }

 private:
  char* data_ = nullptr;
  std::size_t size_ = 0;
  std::FILE* file_;
};

TEST(RunProgress, DurationsReadAsHoursMinutesOrSeconds) {
  EXPECT_EQ(Duration(0.4), "0s");
  EXPECT_EQ(Duration(-3), "0s");
  EXPECT_EQ(Duration(12.4), "12s");
  EXPECT_EQ(Duration(65), "1m05s");
  EXPECT_EQ(Duration(3720), "1h02m");
}

TEST(RunProgress, PlainLinesEveryTenPercentWithTheEtaFromThePaceSoFar) {
  Captured out;
  double wall = 100;  // the test's clock [s]
  RunProgress progress(false, false, out.file(), [&] { return wall; });
  // A 10 s run at 2 wall seconds per simulated second; reported every 0.5 simulated seconds
  // from the first macro step at 0.5 s.
  for (int k = 1; k <= 20; ++k) {
    wall = 100 + 2 * 0.5 * (k - 1);
    progress.Update(0.5 * k, 10);
  }
  const std::string text = out.text();
  // One line per decile, no line twice.
  EXPECT_THAT(text, HasSubstr("progress:  10%  t = 1 s, ETA 18s\n"));  // 1 s taken for 0.5 s
  EXPECT_THAT(text, HasSubstr("progress:  50%  t = 5 s, ETA 10s\n"));  // 9 s for 4.5 s
  EXPECT_THAT(text, HasSubstr("progress:  90%  t = 9 s, ETA 2s\n"));
  EXPECT_THAT(text, HasSubstr("progress: 100%  t = 10 s\n"));  // no ETA at the end
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 10);
}

TEST(RunProgress, NoEtaBeforeHalfASecondAndAResumedRunIsPacedFromWhereItResumed) {
  Captured out;
  double wall = 0;
  RunProgress progress(false, false, out.file(), [&] { return wall; });
  // Resumed at 6 s of a 10 s run: the pace (1 wall second per simulated second) is measured
  // from 6 s, not from 0 s (which would predict 0.67 s left at 8 s instead of 2 s).
  progress.Update(6.0, 10);  // 60 %: the first report, nothing to pace yet
  wall = 0.2;
  progress.Update(7.0, 10);  // 70 %, too early for an estimate
  wall = 2;
  progress.Update(8.0, 10);  // 80 %: 2 s for 2 simulated s, 2 s left
  const std::string text = out.text();
  EXPECT_THAT(text, HasSubstr("progress:  60%  t = 6 s\n"));
  EXPECT_THAT(text, HasSubstr("progress:  70%  t = 7 s\n"));
  EXPECT_THAT(text, HasSubstr("progress:  80%  t = 8 s, ETA 2s\n"));
}

TEST(RunProgress, TheTerminalBarIsRedrawnAtMostTenTimesASecondAndEndsItsLine) {
  Captured out;
  double wall = 0;
  RunProgress progress(false, true, out.file(), [&] { return wall; });
  progress.Update(0.1, 100);  // drawn: the first report
  wall = 0.05;
  progress.Update(0.2, 100);  // within 0.1 s of the last drawing: skipped
  wall = 60;
  progress.Update(30.1, 100);  // 60 s for 30 simulated s: 140 s left
  progress.Done();
  const std::string text = out.text();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\r'), 2) << text;
  EXPECT_THAT(text, Not(HasSubstr("t = 0.2 /")));
  EXPECT_THAT(text,
              HasSubstr("[#########                     ]  30.1%  t = 30.1 / 100 s, ETA 2m20s"));
  EXPECT_EQ(text.back(), '\n');
}

TEST(RunProgress, QuietWritesNothing) {
  Captured out;
  RunProgress progress(true, false, out.file(), [] { return 0.0; });
  progress.Update(5, 10);
  progress.Done();
  EXPECT_EQ(out.text(), "");
}

}  // namespace
}  // namespace gipsi::cli
