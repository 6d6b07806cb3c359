// The haptic loop's real-time option: the ticking thread itself observes the scheduling policy,
// priority and CPU that Stats() reports (SCHED_FIFO when the process may use it, as root here;
// otherwise normal scheduling after one warning). No timing is asserted.

#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "gipsi/haptics/haptic_loop.h"

namespace gipsi {
namespace {

// Records what the ticking thread sees (first tick only; the loop's thread never changes).
class SchedulingProbe final : public HapticRenderer {
 public:
  Vec3 Run(double /*t*/, double /*dt*/) noexcept override {
    if (!seen_.load()) {
      sched_param param{};
      pthread_getschedparam(pthread_self(), &policy_, &param);
      priority_ = param.sched_priority;
      cpu_ = sched_getcpu();
      seen_.store(true);
    }
    return Vec3::Zero();
  }
  std::atomic<bool> seen_{false};
  int policy_ = -1, priority_ = -1, cpu_ = -1;
};

TEST(HapticLoopRealtime, TheTickingThreadRunsWithTheReportedPolicyAndCpu) {
  SchedulingProbe probe;
  HapticRealtime realtime;
  realtime.fifo = true;
  realtime.priority = 20;
  realtime.cpu = 0;
  HapticLoop loop(probe, 1000, 16, realtime);
  loop.Start();
  // Bounded wait for the first tick (1 ms away); 5 s only matter on a stalled machine.
  for (int i = 0; i < 5000 && !probe.seen_.load(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  loop.Stop();
  ASSERT_TRUE(probe.seen_.load());
  const HapticLoopStats s = loop.Stats();
  if (s.fifo) {
    EXPECT_EQ(probe.policy_, SCHED_FIFO);
    EXPECT_EQ(probe.priority_, 20);
  } else {
    EXPECT_EQ(probe.policy_, SCHED_OTHER);  // not permitted: fell back (and warned)
  }
  if (s.pinned) {
    EXPECT_EQ(probe.cpu_, 0);
  }
}

TEST(HapticLoopRealtime, NormalPriorityByDefault) {
  SchedulingProbe probe;
  HapticLoop loop(probe, 1000, 16);
  loop.Start();
  for (int i = 0; i < 5000 && !probe.seen_.load(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  loop.Stop();
  ASSERT_TRUE(probe.seen_.load());
  EXPECT_EQ(probe.policy_, SCHED_OTHER);
  EXPECT_FALSE(loop.Stats().fifo);
  EXPECT_FALSE(loop.Stats().pinned);
}

}  // namespace
}  // namespace gipsi
