#include "gipsi/numerics/sparse/node_block_copy.h"

#include <algorithm>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "gipsi/base/error.h"
#include "gipsi/numerics/simd.h"
#include "gipsi/numerics/sparse/vector_ops.h"

namespace gipsi {
namespace {

// Values past the last block: the AVX kernel loads a block's third column as four doubles.
constexpr std::size_t kPadding = 4;

// The generic product: for each row, y_a = Σ_m (B_m(a,0) x0 + B_m(a,1) x1) + B_m(a,2) x2,
// the blocks in their stored order (column-major: B(a, i) at 3i + a).
void MultiplyGeneric(const int* __restrict start, const int* __restrict column,
                     const double* __restrict values, const double* __restrict x,
                     double* __restrict y, int begin, int end) {
  for (int node = begin; node < end; ++node) {
    const double* __restrict b = values + 9 * std::ptrdiff_t{start[node]};
    double y0 = 0.0, y1 = 0.0, y2 = 0.0;
    for (int m = start[node]; m < start[node + 1]; ++m, b += 9) {
      const double* xj = x + column[m];
      const double x0 = xj[0], x1 = xj[1], x2 = xj[2];
      y0 += b[0] * x0 + b[3] * x1 + b[6] * x2;
      y1 += b[1] * x0 + b[4] * x1 + b[7] * x2;
      y2 += b[2] * x0 + b[5] * x1 + b[8] * x2;
    }
    y[3 * node] = y0;
    y[3 * node + 1] = y1;
    y[3 * node + 2] = y2;
  }
}

#if defined(__x86_64__)
// The same sums with the node's three rows in the first three lanes of a 256-bit register: a
// column of the block times a broadcast x_i, the three products added in the generic order,
// then added to the row sums. No FMA (the target is "avx", not "fma"), so every lane rounds as
// the generic code does. The fourth lane reads the next block's first value (or the padding)
// and is dropped.
__attribute__((target("avx"))) void MultiplyAvx(const int* __restrict start,
                                                const int* __restrict column,
                                                const double* __restrict values,
                                                const double* __restrict x, double* __restrict y,
                                                int begin, int end) {
  for (int node = begin; node < end; ++node) {
    const double* __restrict b = values + 9 * std::ptrdiff_t{start[node]};
    __m256d sum = _mm256_setzero_pd();
    for (int m = start[node]; m < start[node + 1]; ++m, b += 9) {
      const double* xj = x + column[m];
      __m256d t = _mm256_mul_pd(_mm256_loadu_pd(b), _mm256_broadcast_sd(xj));
      t = _mm256_add_pd(t, _mm256_mul_pd(_mm256_loadu_pd(b + 3), _mm256_broadcast_sd(xj + 1)));
      t = _mm256_add_pd(t, _mm256_mul_pd(_mm256_loadu_pd(b + 6), _mm256_broadcast_sd(xj + 2)));
      sum = _mm256_add_pd(sum, t);
    }
    _mm_storeu_pd(y + 3 * node, _mm256_castpd256_pd128(sum));
    _mm_store_sd(y + 3 * node + 2, _mm256_extractf128_pd(sum, 1));
  }
}
#endif

}  // namespace

void NodeBlockCopy::AssignPattern(const SparseMatrix& A) {
  GIPSI_CHECK(HasNodeBlockPattern(A), "NodeBlockCopy: the matrix is not made of 3x3 node blocks");
  const int nodes = static_cast<int>(A.cols() / 3);
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  start_.assign(static_cast<std::size_t>(nodes) + 1, 0);
  source_.resize(static_cast<std::size_t>(nodes));
  column_.clear();
  for (int node = 0; node < nodes; ++node) {
    source_[static_cast<std::size_t>(node)] = outer[3 * node];
    for (int k = outer[3 * node]; k < outer[3 * node + 1]; k += 3) column_.push_back(inner[k]);
    start_[static_cast<std::size_t>(node) + 1] = static_cast<int>(column_.size());
  }
  values_.assign(static_cast<std::size_t>(A.nonZeros()) + kPadding, 0.0);
}

void NodeBlockCopy::CopyValues(const SparseMatrix& A, bool team) {
  const int n = nodes();
  GIPSI_CHECK(
      A.cols() == 3 * n && static_cast<std::size_t>(A.nonZeros()) + kPadding == values_.size(),
      "NodeBlockCopy::CopyValues: the matrix does not have the copied pattern");
  const double* values = A.valuePtr();
  const int* start = start_.data();
  const int* source = source_.data();
  double* blocks = values_.data();
  // Column 3I + a holds A(3J + i, 3I + a) = A(3I + a, 3J + i) (symmetry) at source + 3m + i
  // for the node's block m; the three columns of a node follow each other. Block m keeps
  // A(3I + a, 3J + i) at 9m + 3i + a: its columns are contiguous.
  ForRange(0, n, team && 3 * n >= kMinParallelLength, [=](int node) {
    const int count = start[node + 1] - start[node];
    const double* column = values + source[node];
    double* out = blocks + 9 * std::ptrdiff_t{start[node]};
    for (int a = 0; a < 3; ++a, column += 3 * count)
      for (int m = 0; m < count; ++m)
        for (int i = 0; i < 3; ++i) out[9 * m + 3 * i + a] = column[3 * m + i];
  });
}

void NodeBlockCopy::MultiplyNodes(const double* x, double* y, int begin, int end) const {
#if defined(__x86_64__)
  if (ActiveSimdKernels() == SimdKernels::kAvx) {
    MultiplyAvx(start_.data(), column_.data(), values_.data(), x, y, begin, end);
    return;
  }
#endif
  MultiplyGeneric(start_.data(), column_.data(), values_.data(), x, y, begin, end);
}

void NodeBlockCopy::Multiply(const VecX& x, VecX& y) const {
  const int n = nodes();
  GIPSI_CHECK(x.size() == 3 * n && y.size() == 3 * n && x.data() != y.data(),
              "NodeBlockCopy::Multiply: sizes do not match or x and y alias");
  constexpr int kBatch = 64;
  ForRange(0, (n + kBatch - 1) / kBatch, 3 * n >= kMinParallelLength, [&](int b) {
    MultiplyNodes(x.data(), y.data(), b * kBatch, std::min((b + 1) * kBatch, n));
  });
}

}  // namespace gipsi
