#include "gipsi/numerics/sparse/node_block_copy.h"

#include <algorithm>

#include "gipsi/base/error.h"
#include "gipsi/numerics/sparse/vector_ops.h"

namespace gipsi {

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
  values_.assign(static_cast<std::size_t>(A.nonZeros()), 0.0);
}

void NodeBlockCopy::CopyValues(const SparseMatrix& A, bool team) {
  const int n = nodes();
  GIPSI_CHECK(A.cols() == 3 * n && A.nonZeros() == static_cast<Index>(values_.size()),
              "NodeBlockCopy::CopyValues: the matrix does not have the copied pattern");
  const double* values = A.valuePtr();
  const int* start = start_.data();
  const int* source = source_.data();
  double* blocks = values_.data();
  // Column 3I + a holds A(3J + i, 3I + a) = A(3I + a, 3J + i) (symmetry) at source + 3m + i
  // for the node's block m; the three columns of a node follow each other.
  ForRange(0, n, team && 3 * n >= kMinParallelLength, [=](int node) {
    const int count = start[node + 1] - start[node];
    const double* column = values + source[node];
    double* out = blocks + 9 * std::ptrdiff_t{start[node]};
    for (int a = 0; a < 3; ++a, column += 3 * count)
      for (int m = 0; m < count; ++m)
        for (int i = 0; i < 3; ++i) out[9 * m + 3 * a + i] = column[3 * m + i];
  });
}

void NodeBlockCopy::MultiplyNodes(const double* x, double* y, int begin, int end) const {
  const int* __restrict start = start_.data();
  const int* __restrict column = column_.data();
  const double* __restrict px = x;
  double* __restrict py = y;
  for (int node = begin; node < end; ++node) {
    const double* __restrict b = values_.data() + 9 * std::ptrdiff_t{start[node]};
    double y0 = 0.0, y1 = 0.0, y2 = 0.0;
    for (int m = start[node]; m < start[node + 1]; ++m, b += 9) {
      const double* xj = px + column[m];
      const double x0 = xj[0], x1 = xj[1], x2 = xj[2];
      y0 += b[0] * x0 + b[1] * x1 + b[2] * x2;
      y1 += b[3] * x0 + b[4] * x1 + b[5] * x2;
      y2 += b[6] * x0 + b[7] * x1 + b[8] * x2;
    }
    py[3 * node] = y0;
    py[3 * node + 1] = y1;
    py[3 * node + 2] = y2;
  }
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
