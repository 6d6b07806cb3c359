#pragma once
/// @file
/// OpenMP-parallel vector kernels for the iterative solvers, with deterministic reductions: the
/// index range is split into kSumBlocks contiguous blocks whatever the thread count, each
/// block is summed in index order by whichever thread runs it, and the block sums are added in
/// block order. The result is therefore the same bits on every run and for every thread count,
/// one included (unlike `reduction(+:)`, whose combination order OpenMP leaves unspecified), so
/// a solver may change its team from one call to the next (AdaptiveParallel). Small ranges run
/// on one thread, as one block.

#include <cstddef>
#include <vector>

#include <omp.h>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/numerics/adaptive_parallel.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Ranges shorter than this run serially: a parallel region costs a few microseconds.
inline constexpr Index kMinParallelLength = 8192;

/// Blocks of a deterministic reduction: a multiple of every team size up to 4 (and of 6, 8, 12,
/// 16 and 24), so that a team splits them evenly.
inline constexpr int kSumBlocks = 48;

/// Scratch for deterministic reductions: one cache-line-padded partial sum per block. Not
/// thread-safe; movable.
class ReductionScratch {
 public:
  ReductionScratch() : partials_(static_cast<std::size_t>(kSumBlocks) * kStride, 0.0) {}

  /// The slot of block `b` (< kSumBlocks).
  double& slot(int b) { return partials_[static_cast<std::size_t>(b) * kStride]; }

 private:
  static constexpr std::size_t kStride = 8;  // 64 bytes: no false sharing between slots
  std::vector<double> partials_;
};

/// Σ over the blocks of [0, n) of `block_sum(begin, end)`, computed in parallel as described in
/// the file comment; the same bits for every thread count. `block_sum` may also write to the
/// indices of its block (fused update + reduction). `team` false sums the same blocks on the
/// calling thread (a caller that follows an AdaptiveParallel's choice): the same bits again.
template <class BlockSum>
double DeterministicParallelSum(Index n, ReductionScratch& scratch, BlockSum&& block_sum,
                                bool team = true) {
  if (n < kMinParallelLength) return block_sum(Index{0}, n);
  ForRange(0, kSumBlocks, team, [&](int b) {
    scratch.slot(b) = block_sum(n * b / kSumBlocks, n * (b + 1) / kSumBlocks);
  });
  double sum = 0.0;
  for (int b = 0; b < kSumBlocks; ++b) sum += scratch.slot(b);
  return sum;
}

/// a · b (the same bits for every thread count, and with `team` false on this thread alone).
/// Sizes must match.
inline double ParallelDot(const VecX& a, const VecX& b, ReductionScratch& scratch,
                          bool team = true) {
  const double* __restrict pa = a.data();
  const double* __restrict pb = b.data();
  return DeterministicParallelSum(
      a.size(), scratch,
      [=](Index begin, Index end) {
        double s = 0.0;
        for (Index i = begin; i < end; ++i) s += pa[i] * pb[i];
        return s;
      },
      team);
}

/// y = x + beta * y, in parallel (no reduction).
inline void ParallelXpby(const VecX& x, double beta, VecX& y) {
  const double* __restrict px = x.data();
  double* __restrict py = y.data();
  const Index n = y.size();
  ForRange(Index{0}, n, n >= kMinParallelLength, [=](Index i) { py[i] = px[i] + beta * py[i]; });
}

}  // namespace gipsi
GIPSI_EXPORT_END
