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
///    left to the smoother (a fixed positive scaling of their residual there);
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
/// Cycle: a V-cycle with one damped Jacobi step before and one after the coarse correction on
/// every level, x ← x + ω D⁻¹ (b − A x), with D the 3×3 diagonal blocks where the matrix has
/// that block pattern (the finest level of an FEM tangent) and the diagonal elsewhere, and
/// ω = 4 / (3 · 1.1 λ), λ the power-iteration estimate of λ_max(D⁻¹A) at set-up. The same
/// smoother before and after makes the preconditioner symmetric; it is positive definite
/// when every level's matrix is SPD and ω λ_max(D⁻¹A) < 2 (the smoother converges in the
/// energy norm), which the 10 % margin keeps for the estimate's error and for a finest matrix
/// that drifts from the one the hierarchy was built for (see Refresh). Symmetric Gauss–Seidel
/// was tried first: ~35 % fewer CG iterations, but a serial sweep that ran at under half the
/// speed of an SpMV, for a slower step overall (docs/performance.md).
/// Set-up is serial; the cycle's products and scalings are parallel with every row summed by
/// one thread: the same bits for any thread count.

#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "gipsi/base/export.h"
#include "gipsi/numerics/sparse/linear_solver.h"
#include "gipsi/numerics/sparse/node_block_copy.h"

GIPSI_EXPORT_BEGIN
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
  /// coarse levels and the smoother weights: the V-cycle stays symmetric, and positive
  /// definite for SPD A near the last Setup's matrix (see the file comment); it is a good
  /// preconditioner while A stays close to that matrix. False as for Setup.
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
    /// 3×3 node blocks on this level (block Jacobi, block copy of A): set when every node's
    /// three columns share one sorted row pattern made of whole node blocks (level 0 of an
    /// FEM tangent).
    bool blocked = false;
    std::vector<int> block_diagonal;    ///< per node: offset of its diagonal block in its columns
    std::vector<double> block_inverse;  ///< per node: the inverse of its diagonal block (9)
    NodeBlockCopy copy;                 ///< block-row copy of A (node_block_copy.h)
    double jacobi_weight = 0.0;         ///< ω of the damped-Jacobi smoother
    RowMatrix p;                        ///< prolongator to this level from the next coarser one
    RowMatrix r;                        ///< restriction pᵀ
    VecX x, b, residual;                ///< cycle work vectors
  };

  bool UpdateDiagonal(Level& level) const;
  static void DetectBlocks(Level& level);
  static double JacobiWeight(Level& level, double point_rho);
  static void ApplyBlockInverse(const Level& level, const VecX& r, VecX& z, double weight,
                                bool add);
  static void LevelMultiply(const Level& level, const VecX& x, VecX& y);
  void Cycle(std::size_t l);

  std::vector<std::unique_ptr<Level>> levels_;
  Eigen::MatrixXd near_null_;
  struct CoarseSolver;  ///< CHOLMOD factor of the coarsest matrix (kept out of this header)
  std::unique_ptr<CoarseSolver> coarse_;
  bool ready_ = false;
};

}  // namespace gipsi
GIPSI_EXPORT_END
