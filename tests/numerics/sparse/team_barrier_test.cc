// TeamBarrier (numerics/sparse/team_barrier.h), the meeting point of the fused CG's threads:
// every write made before a round's barrier is seen by every thread after it, for any team
// size, whether the waiting threads spin, yield or sleep. Runs under ThreadSanitizer (the tsan
// preset's thread tests), which would report the plain reads and writes below as races if the
// barrier's ordering were wrong. Plain std::threads: the barrier does not depend on OpenMP.

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "gipsi/numerics/sparse/team_barrier.h"

namespace gipsi {
namespace {

/// Each round every thread writes its slot, meets the others, reads every slot, and meets them
/// again before the next write. Returns the number of stale values any thread read.
int StaleReads(int team, int rounds, int sleeper_every) {
  TeamBarrier barrier;
  std::vector<int> slots(static_cast<std::size_t>(team), -1);
  std::atomic<int> stale{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < team; ++t) {
    threads.emplace_back([&, t] {
      int mine = 0;
      for (int round = 0; round < rounds; ++round) {
        // Now and then one thread arrives late enough (2 ms, past the 50 µs spin budget) for
        // the others to go to sleep.
        if (sleeper_every > 0 && round % sleeper_every == 0 && t == round % team)
          std::this_thread::sleep_for(std::chrono::milliseconds(2));
        slots[static_cast<std::size_t>(t)] = round * team + t;
        barrier.Wait(team);
        for (int k = 0; k < team; ++k)
          if (slots[static_cast<std::size_t>(k)] != round * team + k) ++mine;
        barrier.Wait(team);
      }
      stale += mine;
    });
  }
  for (std::thread& thread : threads) thread.join();
  return stale.load();
}

TEST(TeamBarrier, EveryWriteBeforeARoundIsSeenAfterIt) {
  for (int team : {1, 2, 3, 4}) EXPECT_EQ(StaleReads(team, 2000, 0), 0) << team << " threads";
}

TEST(TeamBarrier, ThreadsThatFellAsleepWakeForTheNextRound) {
  for (int team : {2, 3}) EXPECT_EQ(StaleReads(team, 30, 3), 0) << team << " threads";
}

}  // namespace
}  // namespace gipsi
