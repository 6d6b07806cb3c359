#pragma once
/// @file
/// `TeamBarrier`: a barrier for the threads of one OpenMP team that spins briefly before it
/// sleeps.
///
/// Why not `#pragma omp barrier` or one parallel region per kernel? With
/// OMP_WAIT_POLICY=passive (what GiPSi's scripts set, because spinning OpenMP threads starve
/// their partners on a shared machine), every region start and every OpenMP barrier puts the
/// waiting thread to sleep in the kernel and wakes it with a futex call. On the project's
/// 2-core VM that round trip cost ~20 µs, and a Jacobi-CG iteration of the 20k-tet FEM benchmark
/// had five regions: 42 ms of solve per step against 23 ms with OMP_WAIT_POLICY=active. A CG
/// that keeps one region open and meets here twice per iteration waits only as long as the
/// slower thread needs, and still sleeps (C++20 atomic wait, a futex) when its partner was
/// descheduled for longer than the spin budget, so on a loaded machine a wait holds its core
/// for about the budget at most (its yields give the core to anyone runnable). After a short
/// pause-spin the waiting thread yields between checks: with four threads on the two cores,
/// pause-spinning alone made the 5k-tet step 18.6 ms (4.9 ms with two threads), yielding 7.3 ms.

#include <atomic>
#include <chrono>
#include <thread>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace gipsi {

/// A reusable barrier for the threads of one OpenMP team; not copyable. Every participant
/// passes the team size (omp_get_num_threads(), which may be smaller than the team that was
/// asked for). Wait returns once all of them have called it for this round; its
/// acquire/release ordering makes every write made before the barrier visible after it.
class TeamBarrier {
 public:
  /// How long a waiting thread spins before it sleeps [µs]: about ten CG kernels of a
  /// 5,000-row vector; an imbalance longer than that is a descheduled partner.
  static constexpr int kSpinMicroseconds = 50;
  /// Checks with a pause instruction before the spinning thread starts to yield its core.
  static constexpr int kPauseSpins = 256;

  TeamBarrier() = default;
  TeamBarrier(const TeamBarrier&) = delete;
  TeamBarrier& operator=(const TeamBarrier&) = delete;

  void Wait(int team) {
    if (team <= 1) return;
    const int round = round_.load(std::memory_order_acquire);
    if (arrived_.fetch_add(1, std::memory_order_acq_rel) == team - 1) {
      arrived_.store(0, std::memory_order_relaxed);  // published by the release below
      round_.fetch_add(1, std::memory_order_release);
      round_.notify_all();
      return;
    }
    using Clock = std::chrono::steady_clock;
    const auto give_up = Clock::now() + std::chrono::microseconds(kSpinMicroseconds);
    // Pause-spin first (a partner a few kernels behind arrives within microseconds), then
    // yield between checks: when the team has more threads than the machine has free cores,
    // the partner we wait for may need this very core to arrive.
    for (int spin = 1;; ++spin) {
      if (round_.load(std::memory_order_acquire) != round) return;
      if (spin < kPauseSpins) {
#if defined(__x86_64__) || defined(__i386__)
        _mm_pause();
#endif
        continue;
      }
      std::this_thread::yield();
      if (spin % 16 == 0 && Clock::now() > give_up) break;
    }
    while (round_.load(std::memory_order_acquire) == round)
      round_.wait(round, std::memory_order_acquire);
  }

 private:
  alignas(64) std::atomic<int> arrived_{0};
  alignas(64) std::atomic<int> round_{0};
};

}  // namespace gipsi
