#pragma once
/// @file
/// Smoothed-aggregation algebraic multigrid (SA-AMG) for symmetric positive definite matrices
/// with node blocks (3 DOFs per node for 3-D elasticity), used as the "amg" preconditioner of
/// CG. Internal to the sparse layer: users select it through LinearSolverOptions.
///
/// Set-up (Vaněk, Mandel & Brezina, "Algebraic multigrid by smoothed aggregation for second
/// and fourth order elliptic problems", Computing 56, 1996), level by level:
///  - nodes: consecutive groups of `block_size` rows on the finest level (3 if the row count is
///    a multiple of 3, else 1), aggregates on coarser levels;
///  - strength: nodes I ≠ J are coupled if their block A_IJ has a nonzero entry; nodes with no
///    coupling (e.g. Dirichlet rows replaced by the identity) belong to no aggregate and are
///    left to the smoother, which solves them exactly;
///  - aggregation: the usual three greedy passes in node order (a node whose neighbours are all
///    free seeds an aggregate with them; leftovers join a neighbouring aggregate; what remains
///    forms aggregates with its free neighbours), so the hierarchy is deterministic;
///  - tentative prolongator: per aggregate, a QR factorisation (modified Gram–Schmidt, twice)
///    of the near-null-space vectors restricted to it (rigid-body modes for elasticity when
///    SetNearNullSpace was given them, else the constant per DOF of a node); columns that are
///    numerically dependent are dropped, so a coarse node has ≤ k DOFs;
///  - prolongator smoothing P = (I − ω D⁻¹A) T with ω = 4 / (3 ρ(D⁻¹A)), ρ by power iteration;
///  - Galerkin coarse matrix Pᵀ A P (symmetrised to remove product round-off), until at most
///    `kMaxCoarseRows` rows remain, which CHOLMOD factorises.
/// Cycle: a V-cycle with one forward Gauss–Seidel sweep before and one backward sweep after the
/// coarse correction on every level (by 3×3 node blocks where the matrix has that block
/// pattern, e.g. the finest level of an FEM tangent; point-wise elsewhere), so the
/// preconditioner is symmetric; it is positive
/// definite whenever each level's matrix is SPD (Gauss–Seidel then converges in the energy
/// norm), also when the coarse levels were built from an earlier matrix (see Refresh).
/// Everything is serial except the sparse products, whose rows are each summed by one thread:
/// the same bits for any thread count.

#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "gipsi/numerics/sparse/linear_solver.h"

namespace gipsi {

/// See the file comment. Not copyable; not movable (holds a CHOLMOD factor).
class SmoothedAggregationAmg {
 public:
  /// Coarsening stops at this many rows (the coarse matrix is then factorised).
  static constexpr Index kMaxCoarseRows = 500;
  static constexpr int kMaxLevels = 12;

  SmoothedAggregationAmg();
  SmoothedAggregationAmg(const SmoothedAggregationAmg&) = delete;
  SmoothedAggregationAmg& operator=(const SmoothedAggregationAmg&) = delete;
  ~SmoothedAggregationAmg();

  /// Near-null-space vectors of the matrices to come (rows = matrix rows, k ≤ 12 columns), e.g.
  /// RigidBodyModes; empty restores the default (one constant vector per DOF of a node).
  /// Applies from the next Setup.
  void SetNearNullSpace(const Eigen::MatrixXd& modes);
  /// Builds the hierarchy for A (square, compressed, both triangles stored). Returns false if
  /// a diagonal entry is not positive or a value is not finite (A is not SPD) or the coarsest
  /// factorisation fails; Apply must not be called then.
  [[nodiscard]] bool Setup(const SparseMatrix& A);
  /// Makes A (same pattern as the last Setup's matrix) the finest-level operator and keeps the
  /// coarse levels: the V-cycle stays symmetric positive definite for SPD A and is a good
  /// preconditioner while A stays close to the matrix of the last Setup. False as for Setup.
  [[nodiscard]] bool Refresh(const SparseMatrix& A);
  /// z = B r, one V-cycle from a zero initial guess. r and z must have A's size.
  void Apply(const VecX& r, VecX& z);

  /// y = A x with the finest matrix of the last Setup/Refresh, from the hierarchy's 3×3-block
  /// copy of it (less index traffic than SymmetricSpMV; rows summed by one thread each, so
  /// the bits do not depend on the thread count). Returns false, leaving y alone, if the
  /// finest level has no block copy (no 3×3 node-block pattern). x and y must not alias.
  [[nodiscard]] bool Multiply(const VecX& x, VecX& y) const;

  [[nodiscard]] bool ready() const { return ready_; }
  [[nodiscard]] int num_levels() const { return static_cast<int>(levels_.size()); }
  /// Rows of level l (0 = finest).
  [[nodiscard]] Index rows(int level) const;
  /// Σ nonzeros over levels / nonzeros of the finest matrix.
  [[nodiscard]] double operator_complexity() const;

 private:
  using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
  struct Level {
    SparseMatrix owned;               ///< this level's matrix (coarse levels)
    const SparseMatrix* a = nullptr;  ///< the operator (the caller's matrix on level 0)
    std::vector<int> diagonal;        ///< value index of each diagonal entry
    VecX inverse_diagonal;            ///< 1 / A_ii
    bool sorted = true;               ///< row indices increase within each column
    /// Node-block Gauss–Seidel (3×3 blocks) on this level: set when every node's three columns
    /// share one sorted row pattern made of whole node blocks (FEM tangents on level 0).
    bool blocked = false;
    std::vector<int> block_diagonal;    ///< per node: offset of its diagonal block in its columns
    std::vector<double> block_inverse;  ///< per node: the inverse of its diagonal block (9)
    std::vector<int> block_start;       ///< block copy: first block of each node
    std::vector<int> block_column;      ///< block copy: neighbour node of each block
    std::vector<double> block_values;   ///< block copy: 9 values per block (see UpdateDiagonal)
    RowMatrix p;                        ///< prolongator to this level from the next coarser one
    RowMatrix r;                        ///< restriction pᵀ
    VecX x, b, residual;                ///< cycle work vectors
  };

  bool UpdateDiagonal(Level& level) const;
  static void DetectBlocks(Level& level);
  static void BlockForwardFromZero(Level& level);
  static void BlockBackward(Level& level);
  void Cycle(std::size_t l);

  std::vector<std::unique_ptr<Level>> levels_;
  Eigen::MatrixXd near_null_;
  struct CoarseSolver;  ///< CHOLMOD factor of the coarsest matrix (kept out of this header)
  std::unique_ptr<CoarseSolver> coarse_;
  bool ready_ = false;
};

}  // namespace gipsi
