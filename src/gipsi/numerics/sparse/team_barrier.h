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
/// for about the budget at most. Two measured choices (5k / 20k-tet FEM steps, medians of 3):
///  - No yielding between checks: with two busy processes beside the benchmark, a version that
///    yielded after a short spin measured 154 / 39 ms and then 7.9 / 784 ms (a thread that
///    yielded waits out the other processes' time slices), spin-then-sleep 16 / 57 and
///    16 / 110 ms, and the five regions per iteration before 14.5 / 230 ms. A sleeper that is
///    woken is scheduled promptly; a thread that yielded is not.
///  - No spinning when the team is larger than the cores the process may use (four threads on
///    two cores): spinning made the 5k-tet step 18.6 ms against 4.9 ms with two threads.

#include <atomic>
#include <chrono>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>

#include "gipsi/base/export.h"
#endif

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The number of cores this process may run on (its affinity mask; at least 1), read once.
int AvailableCores();

/// A reusable barrier for the threads of one OpenMP team; not copyable. Every participant
/// passes the team size (omp_get_num_threads(), which may be smaller than the team that was
/// asked for). Wait returns once all of them have called it for this round; its
/// acquire/release ordering makes every write made before the barrier visible after it.
class TeamBarrier {
 public:
  /// How long a waiting thread spins before it sleeps [µs]: about ten CG kernels of a
  /// 5,000-row vector; an imbalance longer than that is a descheduled partner.
  static constexpr int kSpinMicroseconds = 50;

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
    // Spin only while the team fits the cores this process may use: a team larger than that
    // waits for a partner that may need this very core to arrive, so it sleeps at once.
    if (team <= AvailableCores()) {
      using Clock = std::chrono::steady_clock;
      const auto give_up = Clock::now() + std::chrono::microseconds(kSpinMicroseconds);
      for (int spin = 1;; ++spin) {
        if (round_.load(std::memory_order_acquire) != round) return;
#if defined(__x86_64__) || defined(__i386__)
        _mm_pause();
#endif
        if (spin % 64 == 0 && Clock::now() > give_up) break;
      }
    }
    while (round_.load(std::memory_order_acquire) == round)
      round_.wait(round, std::memory_order_acquire);
  }

 private:
  alignas(64) std::atomic<int> arrived_{0};
  alignas(64) std::atomic<int> round_{0};
};

}  // namespace gipsi
GIPSI_EXPORT_END
