#pragma once
/// @file
/// `AdaptiveParallel`: decides, call by call, whether a loop runs on the OpenMP team or on the
/// calling thread alone, by the wall time each way has taken lately.
///
/// Why: on a machine with a busy neighbour, one thread of a two-thread team is often
/// descheduled, and a parallel region then lasts until that thread gets a time slice back
/// (several ms), whatever its work. A cheap loop opened as a region every time step became the
/// run's bottleneck: the TTP06 slab's activation tracking (about 40 µs of work per step) took
/// 37.9 s instead of 0.17 s while a two-thread benchmark ran beside it. A thread count chosen
/// once cannot fit both a quiet and a busy machine, and the load changes during a run, so each
/// call site measures both ways and keeps the faster one.
///
/// The rule: run the way whose recent calls were faster (exponential moving averages of the
/// call's wall time); now and then run the other way once, to notice when the machine changes.
/// A probe is due once the calls since the last one have taken kProbeRatio times what the other
/// way is expected to take, so probing costs at most about 1/kProbeRatio of the run whatever
/// the two ways cost: beside a busy neighbour a 10-µs serial loop whose parallel form waits
/// 5 ms for a time slice is probed every 0.3 s, not every few calls. When the machine quietens,
/// the faster team is noticed within that time.
///
/// Use it only for loops whose results do not depend on the number of threads (each item
/// written by one iteration, or sums over fixed blocks added in block order, as in
/// numerics/sparse/vector_ops.h): switching must never change a result's bits.

#include <chrono>
#include <cstdint>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The OpenMP team size a parallel region would get now (omp_get_max_threads(); 1 without
/// OpenMP).
int MaxTeamThreads();

/// Runs `body(i)` for i in [begin, end): as an OpenMP loop (static schedule) when `parallel`,
/// else as a plain loop on the calling thread. Use it instead of `#pragma omp parallel for
/// if (...)`: a region whose `if` is false still runs through libgomp's team start and end,
/// and the end wakes the team barrier's futex even for a team of one: a system call, about
/// 1.5 µs on this project's VM (a plain 64-item loop: 0.01 µs). The heart demo's small loops
/// made about 190,000 such calls in 4 s of simulated time (docs/performance.md).
template <class I, class Body>
inline void ForRange(I begin, I end, bool parallel, Body&& body) {
  if (parallel) {
#pragma omp parallel for schedule(static)
    for (I i = begin; i < end; ++i) body(i);
  } else {
    for (I i = begin; i < end; ++i) body(i);
  }
}

/// Per call site; not thread-safe (one object's step calls it). A copy carries on with the
/// same measurements.
class AdaptiveParallel {
 public:
  /// The first probe of the other way comes after this many calls; later ones after the
  /// preferred way's calls took kProbeRatio times the other way's expected time.
  static constexpr int kFirstProbe = 2;
  static constexpr double kProbeRatio = 64;

  /// Starts a call: whether to run it on the team. `eligible`: the loop is long enough to be
  /// worth a team at all (and the team has more than one thread); when false the call runs
  /// serially and is not timed. Call End() after the loop.
  [[nodiscard]] bool Begin(bool eligible);
  /// Ends the call begun by Begin and records its wall time per unit of work done (`units`,
  /// e.g. iterations, when calls do different amounts of work).
  void End(double units = 1);

  /// The way the next eligible call would run, without a probe (for tests and profiles).
  [[nodiscard]] bool prefers_parallel() const { return prefer_parallel_; }
  /// Eligible calls that ran on the team / serially so far.
  [[nodiscard]] std::int64_t parallel_calls() const { return calls_[1]; }
  [[nodiscard]] std::int64_t serial_calls() const { return calls_[0]; }

  /// The decision rule without the clock, for tests: records that a call that ran `parallel`
  /// took `seconds`.
  void Record(bool parallel, double seconds);
  /// Whether the next eligible call runs on the team (counts it as started).
  [[nodiscard]] bool Next();

 private:
  using Clock = std::chrono::steady_clock;
  double average_[2] = {-1, -1};  // [serial, parallel] mean call time [s]; -1: not measured
  std::int64_t calls_[2] = {0, 0};
  bool prefer_parallel_ = true;
  int calls_since_probe_ = 0;
  double time_since_probe_ = 0;  // [s] of the preferred way's calls since the last probe
  bool timing_ = false, running_parallel_ = false;
  Clock::time_point start_{};
};

}  // namespace gipsi
GIPSI_EXPORT_END
