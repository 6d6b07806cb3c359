// Symmetric sparse matrix-vector products, row-parallel over the columns of a full symmetric
// CSC matrix (column j of a symmetric matrix is row j): a general one, and one for matrices
// made of 3×3 node blocks (FEM tangents) that loads one row index per block.

#include <algorithm>

#include "gipsi/base/error.h"
#include "gipsi/numerics/sparse/linear_solver.h"
#include "gipsi/numerics/sparse/vector_ops.h"

namespace gipsi {

namespace {
/// Rows per scheduling unit of the parallel loops (keeps one function call per batch).
constexpr int kSpMVRowBatch = 64;

/// y of nodes [begin, end) for NodeBlockSpMV (rows 3·begin to 3·end); serial.
void NodeBlockSpMVNodes(const SparseMatrix& A, const double* x, double* y, int begin, int end) {
  const int* __restrict outer = A.outerIndexPtr();
  const int* __restrict inner = A.innerIndexPtr();
  const double* __restrict values = A.valuePtr();
  const double* __restrict px = x;
  double* __restrict py = y;
  // Column 3I + k of a symmetric matrix is its row 3I + k; the three columns of node I share
  // one row list, so one index load serves the nine entries of a block.
  for (int node = begin; node < end; ++node) {
    const int c0 = outer[3 * node];
    const int length = outer[3 * node + 1] - c0;
    const double* __restrict v0 = values + c0;
    const double* __restrict v1 = values + outer[3 * node + 1];
    const double* __restrict v2 = values + outer[3 * node + 2];
    const int* __restrict rows = inner + c0;
    double a0 = 0.0, a1 = 0.0, a2 = 0.0, b0 = 0.0, b1 = 0.0, b2 = 0.0;
    for (int t = 0; t < length; t += 3) {
      const double* xj = px + rows[t];
      const double x0 = xj[0], x1 = xj[1], x2 = xj[2];
      a0 += v0[t] * x0 + v0[t + 1] * x1;
      a1 += v1[t] * x0 + v1[t + 1] * x1;
      a2 += v2[t] * x0 + v2[t + 1] * x1;
      b0 += v0[t + 2] * x2;
      b1 += v1[t + 2] * x2;
      b2 += v2[t + 2] * x2;
    }
    py[3 * node] = a0 + b0;
    py[3 * node + 1] = a1 + b1;
    py[3 * node + 2] = a2 + b2;
  }
}

}  // namespace

void SymmetricSpMVRows(const SparseMatrix& A, const double* x, double* y, int begin, int end) {
  const int* __restrict outer = A.outerIndexPtr();
  const int* __restrict inner = A.innerIndexPtr();
  const double* __restrict values = A.valuePtr();
  const double* __restrict px = x;
  double* __restrict py = y;
  // Four partial sums per row break the floating-point add dependency chain, which otherwise
  // bounds one core at ~12 GB/s (measured 16-17 GB/s with four, single-threaded, 40³ lattice).
  // The combination order is fixed, so each y[j] does not depend on the thread count.
  for (int j = begin; j < end; ++j) {
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    int k = outer[j];
    const int last = outer[j + 1];
    for (; k + 4 <= last; k += 4) {
      s0 += values[k] * px[inner[k]];
      s1 += values[k + 1] * px[inner[k + 1]];
      s2 += values[k + 2] * px[inner[k + 2]];
      s3 += values[k + 3] * px[inner[k + 3]];
    }
    for (; k < last; ++k) s0 += values[k] * px[inner[k]];
    py[j] = (s0 + s1) + (s2 + s3);
  }
}

void SymmetricSpMV(const SparseMatrix& A, const VecX& x, VecX& y, bool team) {
  GIPSI_CHECK(A.rows() == A.cols(), "SymmetricSpMV: matrix is {}x{}, not square", A.rows(),
              A.cols());
  GIPSI_CHECK(x.size() == A.cols() && y.size() == A.rows(),
              "SymmetricSpMV: sizes do not match (A {}x{}, x {}, y {})", A.rows(), A.cols(),
              x.size(), y.size());
  GIPSI_CHECK(A.isCompressed(), "SymmetricSpMV: matrix must be compressed");
  GIPSI_CHECK(x.data() != y.data() || x.size() == 0, "SymmetricSpMV: x and y alias");

  const int n = static_cast<int>(A.cols());
  const int batches = (n + kSpMVRowBatch - 1) / kSpMVRowBatch;
  ForRange(0, batches, team && n >= kMinParallelLength, [&](int b) {
    const int t = b * kSpMVRowBatch;
    SymmetricSpMVRows(A, x.data(), y.data(), t, std::min(t + kSpMVRowBatch, n));
  });
}

bool HasNodeBlockPattern(const SparseMatrix& A) {
  if (A.rows() != A.cols() || !A.isCompressed() || A.rows() % 3 != 0) return false;
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const int nodes = static_cast<int>(A.rows() / 3);
  for (int node = 0; node < nodes; ++node) {
    const int c0 = outer[3 * node];
    const int length = outer[3 * node + 1] - c0;
    if (length % 3 != 0) return false;
    for (int a = 1; a < 3; ++a) {
      const int ca = outer[3 * node + a];
      if (outer[3 * node + a + 1] - ca != length ||
          !std::equal(inner + c0, inner + c0 + length, inner + ca))
        return false;
    }
    bool diagonal = false;
    for (int t = 0; t < length; t += 3) {
      const int row = inner[c0 + t];
      if (row % 3 != 0 || inner[c0 + t + 1] != row + 1 || inner[c0 + t + 2] != row + 2)
        return false;
      if (t > 0 && row <= inner[c0 + t - 1]) return false;
      diagonal = diagonal || row == 3 * node;
    }
    if (!diagonal) return false;
  }
  return true;
}

void NodeBlockSpMV(const SparseMatrix& A, const VecX& x, VecX& y) {
  GIPSI_CHECK(A.rows() == A.cols() && A.rows() % 3 == 0 && x.size() == A.cols() &&
                  y.size() == A.rows() && (x.data() != y.data() || x.size() == 0),
              "NodeBlockSpMV: sizes do not match (A {}x{}, x {}, y {}) or x and y alias", A.rows(),
              A.cols(), x.size(), y.size());
  const int nodes = static_cast<int>(A.cols() / 3);
  const int batches = (nodes + kSpMVRowBatch - 1) / kSpMVRowBatch;
  ForRange(0, batches, 3 * nodes >= kMinParallelLength, [&](int b) {
    const int t = b * kSpMVRowBatch;
    NodeBlockSpMVNodes(A, x.data(), y.data(), t, std::min(t + kSpMVRowBatch, nodes));
  });
}

}  // namespace gipsi
