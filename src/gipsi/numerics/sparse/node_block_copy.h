#pragma once
/// @file
/// `NodeBlockCopy`: a block-row (BSR) copy of a symmetric matrix made of 3×3 node blocks (an
/// FEM tangent, HasNodeBlockPattern), for the products CG repeats with one matrix.
///
/// Why a copy: in compressed columns the nine entries of a block lie in three columns, so a
/// product streams three runs of values per node and loads each block row index once per
/// column list. In the copy the nine values of a block are contiguous and every block has one
/// column index: one stream, fewer loads per block. Measured with fem_bench's BM_TangentSpMV
/// (2 threads, medians of 5): 132 → 85 µs on the 20k-tet tangent, 380 → 265 µs on the 78k-tet
/// one. The copy costs one parallel pass over the values per Factorize, against the 80-250
/// products a Jacobi-CG solve of those meshes makes with them.

#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/numerics/sparse/linear_solver.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class NodeBlockCopy {
 public:
  /// Builds the block pattern of A (HasNodeBlockPattern(A) must hold: checked); the values
  /// come with the next CopyValues.
  void AssignPattern(const SparseMatrix& A);
  /// AssignPattern(A), then CopyValues(A).
  void Assign(const SparseMatrix& A) {
    AssignPattern(A);
    CopyValues(A);
  }
  /// Copies the values of A, which has the pattern of the last Assign (only the sizes are
  /// checked). Parallel over nodes, unless `team` is false (then on the calling thread).
  void CopyValues(const SparseMatrix& A, bool team = true);
  /// y = A x for the rows of nodes [begin, end) (rows 3·begin to 3·end); serial. Each entry is
  /// summed in a fixed order, so its bits do not depend on how callers split the nodes, nor on
  /// whether the AVX kernel runs (numerics/simd.h).
  void MultiplyNodes(const double* x, double* y, int begin, int end) const;
  /// y = A x, parallel over nodes (OpenMP). x and y must have 3·nodes() entries.
  void Multiply(const VecX& x, VecX& y) const;

  [[nodiscard]] int nodes() const {
    return start_.empty() ? 0 : static_cast<int>(start_.size()) - 1;
  }
  /// First block of each node (nodes() + 1 entries): the work of a node range for splits.
  [[nodiscard]] const std::vector<int>& block_start() const { return start_; }

 private:
  std::vector<int> start_;   ///< first block of each node, then the block count
  std::vector<int> column_;  ///< 3 × the neighbour node J of each block (its first row)
  /// block m of node I: A(3I + a, 3J + i) at 9m + 3i + a (column-major blocks), then zeros
  std::vector<double> values_;
  std::vector<int> source_;  ///< per node: where its first column starts in A's values
};

}  // namespace gipsi
GIPSI_EXPORT_END
