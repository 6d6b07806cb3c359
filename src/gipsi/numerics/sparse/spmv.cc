// Symmetric sparse matrix-vector product, row-parallel over the columns of a full symmetric
// CSC matrix (column j of a symmetric matrix is row j).

#include "gipsi/base/error.h"
#include "gipsi/numerics/sparse/linear_solver.h"
#include "gipsi/numerics/sparse/vector_ops.h"

namespace gipsi {

void SymmetricSpMV(const SparseMatrix& A, const VecX& x, VecX& y) {
  GIPSI_CHECK(A.rows() == A.cols(), "SymmetricSpMV: matrix is {}x{}, not square", A.rows(),
              A.cols());
  GIPSI_CHECK(x.size() == A.cols() && y.size() == A.rows(),
              "SymmetricSpMV: sizes do not match (A {}x{}, x {}, y {})", A.rows(), A.cols(),
              x.size(), y.size());
  GIPSI_CHECK(A.isCompressed(), "SymmetricSpMV: matrix must be compressed");
  GIPSI_CHECK(x.data() != y.data() || x.size() == 0, "SymmetricSpMV: x and y alias");

  const int n = static_cast<int>(A.cols());
  const int* __restrict outer = A.outerIndexPtr();
  const int* __restrict inner = A.innerIndexPtr();
  const double* __restrict values = A.valuePtr();
  const double* __restrict px = x.data();
  double* __restrict py = y.data();
  // Each y[j] is one sequential sum, so the result does not even depend on the thread count.
#pragma omp parallel for schedule(static) if (n >= kMinParallelLength)
  for (int j = 0; j < n; ++j) {
    double sum = 0.0;
    const int end = outer[j + 1];
    for (int k = outer[j]; k < end; ++k) sum += values[k] * px[inner[k]];
    py[j] = sum;
  }
}

}  // namespace gipsi
