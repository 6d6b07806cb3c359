#pragma once
/// @file
/// OpenMP-parallel vector kernels for the iterative solvers, with deterministic reductions: the
/// index range is split into one contiguous block per thread, each thread sums its block in
/// index order, and the per-thread partial sums are added in thread order. The result is
/// therefore the same bits on every run with the same thread count (unlike `reduction(+:)`,
/// whose combination order OpenMP leaves unspecified). Small ranges run on one thread.

#include <cstddef>
#include <vector>

#include <omp.h>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Ranges shorter than this run serially: a parallel region costs a few microseconds.
inline constexpr Index kMinParallelLength = 8192;

/// Scratch for deterministic reductions: one cache-line-padded partial sum per thread.
/// Grows (allocates) only when the OpenMP thread count grows. Not thread-safe; movable.
class ReductionScratch {
 public:
  /// Sized for the current `omp_get_max_threads()`.
  ReductionScratch() { Reserve(omp_get_max_threads()); }

  /// Makes room for `threads` partial sums (allocates only if it grows).
  void Reserve(int threads) {
    const std::size_t need = static_cast<std::size_t>(threads) * kStride;
    if (partials_.size() < need) partials_.assign(need, 0.0);
  }
  /// The slot of thread `t`.
  double& slot(int t) { return partials_[static_cast<std::size_t>(t) * kStride]; }

 private:
  static constexpr std::size_t kStride = 8;  // 64 bytes: no false sharing between slots
  std::vector<double> partials_;
};

/// Σ over the blocks of [0, n) of `block_sum(begin, end)`, computed in parallel as described in
/// the file comment; deterministic for a fixed thread count. `block_sum` may also write to
/// the indices of its block (fused update + reduction).
template <class BlockSum>
double DeterministicParallelSum(Index n, ReductionScratch& scratch, BlockSum&& block_sum) {
  if (n < kMinParallelLength) return block_sum(Index{0}, n);
  const int max_threads = omp_get_max_threads();
  scratch.Reserve(max_threads);
  int team = 1;
#pragma omp parallel num_threads(max_threads)
  {
    const int t = omp_get_thread_num();
    const int count = omp_get_num_threads();
    const Index begin = n * t / count;
    const Index end = n * (t + 1) / count;
    scratch.slot(t) = block_sum(begin, end);
    if (t == 0) team = count;
  }
  double sum = 0.0;
  for (int t = 0; t < team; ++t) sum += scratch.slot(t);
  return sum;
}

/// a · b (deterministic for a fixed thread count). Sizes must match.
inline double ParallelDot(const VecX& a, const VecX& b, ReductionScratch& scratch) {
  const double* __restrict pa = a.data();
  const double* __restrict pb = b.data();
  return DeterministicParallelSum(a.size(), scratch, [=](Index begin, Index end) {
    double s = 0.0;
    for (Index i = begin; i < end; ++i) s += pa[i] * pb[i];
    return s;
  });
}

/// y = x + beta * y, in parallel (no reduction).
inline void ParallelXpby(const VecX& x, double beta, VecX& y) {
  const double* __restrict px = x.data();
  double* __restrict py = y.data();
  const Index n = y.size();
#pragma omp parallel for schedule(static) if (n >= kMinParallelLength)
  for (Index i = 0; i < n; ++i) py[i] = px[i] + beta * py[i];
}

}  // namespace gipsi
GIPSI_EXPORT_END
