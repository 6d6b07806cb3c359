// AdaptiveParallel's rule, driven with given call times (no clock): on a quiet machine the team
// wins and serial probes cost under 1 %; beside a busy neighbour (a region waits for a time
// slice) the calling thread wins at the first probe and parallel probes become rare; a change
// of load during a run is followed. ForRange: a serial choice opens no OpenMP region.

#include "gipsi/numerics/adaptive_parallel.h"

#include <vector>

#include <gtest/gtest.h>
#include <omp.h>

namespace gipsi {
namespace {

/// Runs `calls` eligible calls that take `parallel_s` on the team and `serial_s` alone; returns
/// the total time they took.
double Drive(AdaptiveParallel& loop, int calls, double parallel_s, double serial_s) {
  double total = 0;
  for (int k = 0; k < calls; ++k) {
    const bool parallel = loop.Next();
    const double t = parallel ? parallel_s : serial_s;
    loop.Record(parallel, t);
    total += t;
  }
  return total;
}

TEST(AdaptiveParallel, OnAQuietMachineTheTeamWinsAndSerialProbesBecomeRare) {
  AdaptiveParallel loop;
  const double total = Drive(loop, 10000, 1.0e-3, 1.8e-3);
  EXPECT_TRUE(loop.prefers_parallel());
  // A serial probe each time the team's calls have taken 64 × 1.8 ms: every 116 calls.
  EXPECT_LE(loop.serial_calls(), 10000 / 115 + 1);
  EXPECT_LT(total, 10000 * 1.0e-3 * 1.01);  // the probes cost under 1 %
}

TEST(AdaptiveParallel, BesideABusyNeighbourTheCallingThreadWinsAtTheFirstProbe) {
  // The TTP06 slab's tracking loop: ~40 µs alone, a 4 ms time slice when a region waits for a
  // descheduled thread.
  AdaptiveParallel loop;
  const double total = Drive(loop, 10000, 4e-3, 40e-6);
  EXPECT_FALSE(loop.prefers_parallel());
  // The first call, then a parallel probe each time the serial calls have taken 64 × 4 ms
  // (6,400 calls).
  EXPECT_LE(loop.parallel_calls(), 1 + 2);
  // Against 40 s had every call run on the team: within 10 % of running serially throughout.
  EXPECT_LT(total, 1.1 * 10000 * 40e-6);
}

TEST(AdaptiveParallel, FollowsTheMachineWhenANeighbourStartsAndStops) {
  AdaptiveParallel loop;
  Drive(loop, 2000, 1.0e-3, 1.8e-3);
  ASSERT_TRUE(loop.prefers_parallel());
  // A neighbour starts: the team's average passes the serial figure within a few calls.
  const auto serial_before = loop.serial_calls();
  Drive(loop, 3, 4e-3, 1.8e-3);
  EXPECT_FALSE(loop.prefers_parallel());
  Drive(loop, 1000, 4e-3, 1.8e-3);
  EXPECT_FALSE(loop.prefers_parallel());
  EXPECT_GT(loop.serial_calls() - serial_before, 950);
  // It stops: the next parallel probe, once the serial calls have taken 64 times the team's
  // last figure (at most 64 × 4 ms / 1.8 ms = 143 calls), wins it back.
  Drive(loop, 145, 1.0e-3, 1.8e-3);
  EXPECT_TRUE(loop.prefers_parallel());
}

TEST(AdaptiveParallel, ALoopTooShortForATeamRunsSeriallyAndIsNotTimed) {
  AdaptiveParallel loop;
  EXPECT_FALSE(loop.Begin(false));
  loop.End();
  EXPECT_EQ(loop.parallel_calls() + loop.serial_calls(), 0);
  EXPECT_TRUE(loop.Begin(true));  // the first eligible call tries the team
  loop.End();
  EXPECT_EQ(loop.parallel_calls(), 1);
}

// A serial choice must not enter libgomp at all (its region end costs a system call even for
// a team of one), and a parallel one must run every index exactly once on the team.
TEST(ForRange, ASerialChoiceOpensNoRegionAndAParallelOneCoversEveryIndexOnce) {
  const int n = 1000;
  std::vector<int> level(n, -1), hits(n, 0);
  ForRange(0, n, false, [&](int i) {
    level[static_cast<std::size_t>(i)] = omp_get_level();
    ++hits[static_cast<std::size_t>(i)];
  });
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(level[static_cast<std::size_t>(i)], 0) << "index " << i << " ran inside a region";
    ASSERT_EQ(hits[static_cast<std::size_t>(i)], 1);
  }

  std::vector<int> thread(n, -1);
  hits.assign(n, 0);
  ForRange(0, n, true, [&](int i) {
    level[static_cast<std::size_t>(i)] = omp_get_level();
    thread[static_cast<std::size_t>(i)] = omp_get_thread_num();
    ++hits[static_cast<std::size_t>(i)];  // each index belongs to one thread: no race
  });
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(level[static_cast<std::size_t>(i)], 1) << "index " << i << " ran outside a region";
    ASSERT_EQ(hits[static_cast<std::size_t>(i)], 1) << "index " << i;
  }
  // A static schedule: the team's threads take contiguous, increasing ranges.
  for (int i = 1; i < n; ++i)
    ASSERT_GE(thread[static_cast<std::size_t>(i)], thread[static_cast<std::size_t>(i) - 1]);
  // The empty range runs nothing either way.
  ForRange(5, 5, true, [&](int) { ADD_FAILURE() << "ran an index of an empty range"; });
  ForRange(5, 5, false, [&](int) { ADD_FAILURE() << "ran an index of an empty range"; });
}

}  // namespace
}  // namespace gipsi
