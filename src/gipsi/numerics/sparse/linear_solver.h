#pragma once
/// @file
/// Sparse symmetric positive definite linear solvers behind one interface: preconditioned
/// conjugate gradients (Jacobi, incomplete Cholesky, or a lagged sparse Cholesky factorisation
/// reused across many matrices) and direct sparse Cholesky/LDLᵀ (Eigen's simplicial LDLᵀ and
/// SuiteSparse CHOLMOD). Usage for a sequence of matrices with one sparsity pattern:
///
///     auto solver = MakeLinearSolver(options);
///     solver->AnalyzePattern(A);          // once per pattern (symbolic factorisation, ordering)
///     for (each step) {
///       if (!solver->Factorize(A)) ...    // new values: numeric factorisation / preconditioner
///       LinearSolveStats s = solver->Solve(b, x);   // x: initial guess in, solution out
///     }

#include <memory>
#include <string>
#include <string_view>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class StateReader;
class StateWriter;

/// Square sparse matrix, compressed columns, 32-bit indices. Symmetric matrices store both
/// triangles, so a column is also a row (SpMV can run row-parallel).
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

/// y = A x for a symmetric A stored in full (both triangles); parallel over rows (OpenMP,
/// static schedule: the same bits for the same thread count; in fact each y[j] is summed by one
/// thread in a fixed order, so the bits do not depend on the thread count either). Preconditions
/// (checked): A is square and compressed, x.size() == y.size() == A.rows() (y is not resized), x
/// and y are distinct vectors. Allocates nothing. `team` false runs it on the calling thread
/// (a caller that follows an AdaptiveParallel's choice beside a busy neighbour); the bits are
/// the same either way.
void SymmetricSpMV(const SparseMatrix& A, const VecX& x, VecX& y, bool team = true);

/// True if A (square, compressed) has the node-block pattern of a matrix assembled from 3×3
/// node blocks: the row count is a multiple of 3, the three columns 3I, 3I + 1, 3I + 2 of every
/// node I hold one list of rows, sorted, made of whole blocks (3J, 3J + 1, 3J + 2), including
/// the diagonal block. TetAssembly::MakePattern has it. O(nonzeros).
[[nodiscard]] bool HasNodeBlockPattern(const SparseMatrix& A);

/// y = A x as SymmetricSpMV, for a symmetric A with HasNodeBlockPattern(A) (the caller checks
/// that once per pattern; only the sizes are checked here): one row-index load per 3×3 block
/// and each x_J loaded once for the node's three rows, about a quarter less memory traffic
/// than SymmetricSpMV. Each y entry is summed by one thread in a fixed order (its own,
/// different from SymmetricSpMV's), so the bits do not depend on the thread count. Allocates
/// nothing.
void NodeBlockSpMV(const SparseMatrix& A, const VecX& x, VecX& y);

/// The serial kernel of SymmetricSpMV, for callers that split the work themselves (the fused
/// CG): y_j for rows j in [begin, end). Same preconditions as SymmetricSpMV, not checked; each
/// y entry gets the same bits as there.
void SymmetricSpMVRows(const SparseMatrix& A, const double* x, double* y, int begin, int end);

/// Which solver and how hard it works. Plain struct.
struct LinearSolverOptions {
  /// "cg" (preconditioned CG), "ldlt" (Eigen SimplicialLDLT), "cholmod" (SuiteSparse CHOLMOD
  /// supernodal LLᵀ), "umfpack" (UMFPACK LU with pivoting: saddle points, any nonsingular) or
  /// "schur_gmres" (GMRES with a block preconditioner, for a MixedSolid's saddle points only:
  /// saddle_point_solver.h; MakeLinearSolver refuses it).
  std::string type = "cg";
  /// For "cg": "none", "jacobi" (runs the fused single-region CG, pcg.cc), "sgs" (the default:
  /// symmetric block Gauss-Seidel on 3×3 node blocks in Eisenstat's form, node_block_sgs.h;
  /// 2.4-2.7× fewer iterations than Jacobi on FEM tangents, 18-21 % less time per FEM step on
  /// one core and up to 24 % on two (docs/performance.md); its sweeps are sequential within a
  /// domain of 12,288 rows, so a smaller system solves on one thread, where many threads may
  /// make Jacobi faster; a matrix not made of node blocks gets Jacobi, with Jacobi's bits),
  /// "ic" (incomplete Cholesky), "cholesky" (a CHOLMOD
  /// factorisation of an earlier matrix, refreshed when CG needs more than
  /// `refactor_iterations` iterations with it, or when a solve needs at least the mean
  /// iterations per solve since the factorisation, the factorisation counted as its flops in
  /// CG iterations: the amortised rule, see pcg.cc) or "amg" (smoothed-aggregation algebraic
  /// multigrid on 3×3 node blocks, one damped-Jacobi V-cycle per CG iteration; its
  /// coarse levels are built from an earlier matrix and rebuilt under the same rule as
  /// "cholesky", the finest level always uses the current matrix). "ic" refactorises every
  /// step and cost 5-7× more than Jacobi on the FEM benchmark.
  std::string preconditioner = "sgs";
  /// CG stops when ‖b − A x‖ ≤ tolerance · ‖b‖ (the true residual, checked with an SpMV; the
  /// initial residual counts, so a good warm start can take 0 iterations). Direct solvers
  /// report `converged` only if their residual also meets it.
  double tolerance = 1e-6;
  /// CG iteration budget per Solve (≥ 1).
  int max_iterations = 2000;
  /// For preconditioners "cholesky" and "amg": a Solve needing more CG iterations than this
  /// (or not converging) makes the next Factorize refactorise numerically / rebuild the
  /// multigrid hierarchy (≥ 0).
  int refactor_iterations = 30;
};

/// What one Solve did. Plain struct.
struct LinearSolveStats {
  bool converged = false;  ///< the residual meets LinearSolverOptions::tolerance
  int iterations = 0;      ///< CG iterations (0 for direct solvers)
  /// ‖b − A x‖ / ‖b‖ at exit, always from the true residual (0 if b = 0; NaN or ∞ if b or
  /// the iterate is not finite; +∞ if Solve ran without a successful Factorize).
  double relative_residual = 0;
  /// A numeric factorisation ran (successfully or not) in the last Factorize: always for
  /// "ldlt", "cholmod" and "cg+ic", never for "cg+none"/"cg+jacobi", and for "cg+cholesky"
  /// and "cg+amg" (hierarchy set-up) on the first Factorize and when the previous Solve asked
  /// for a refresh.
  bool refactorized = false;
};

/// Not copyable (holds factorisations); not movable.
class LinearSolver {
 public:
  LinearSolver() = default;
  LinearSolver(const LinearSolver&) = delete;
  LinearSolver& operator=(const LinearSolver&) = delete;
  virtual ~LinearSolver() = default;

  /// E.g. "cg+ic", "cholmod".
  [[nodiscard]] virtual std::string name() const = 0;
  /// Vectors that the matrices to come nearly annihilate (rows = matrix rows, at most 12
  /// columns; e.g. RigidBodyModes for elasticity). Only "cg+amg" uses them (from the next
  /// hierarchy set-up; without them it assumes 3 DOFs per node and the 3 translations); the
  /// others ignore the call.
  virtual void SetNearNullSpace(const Eigen::MatrixXd& /*modes*/) {}
  /// From now on, accepts symmetric indefinite (nonsingular) matrices where the method can:
  /// "ldlt" factorises them without pivoting (a pivot below 1e-13 of the largest in magnitude
  /// still fails); "cholmod" tries its supernodal LLᵀ and falls back to that LDLᵀ for a matrix
  /// that is not positive definite. Returns whether the solver can; the others are for SPD
  /// matrices only.
  virtual bool AcceptIndefinite() { return false; }
  /// Symbolic analysis (ordering, elimination tree) for matrices with A's pattern. Call again
  /// only when the pattern changes (it also drops any factorisation). A must be square and
  /// compressed (checked).
  virtual void AnalyzePattern(const SparseMatrix& A) = 0;
  /// Numeric set-up for A (same pattern as analysed; the size and nonzero count are checked,
  /// and a Factorize without any earlier AnalyzePattern analyses A first). All solvers keep a
  /// pointer to A (iterative ones to multiply, direct ones to measure the residual): it must
  /// stay alive and unchanged until the next Factorize. Returns false if A has a non-finite
  /// value or is found not to be positive definite (a failed factorisation, a non-positive
  /// LDLᵀ pivot or Jacobi diagonal entry, or an incomplete Cholesky that fails even with
  /// Eigen's diagonal shifts); Solve then reports not converged until a Factorize succeeds.
  /// Never throws.
  [[nodiscard]] virtual bool Factorize(const SparseMatrix& A) = 0;
  /// Solves A x = b for the last factorised A. On entry x is the initial guess (warm start;
  /// direct solvers ignore it; a CG guess of the wrong size is replaced by zeros). b must
  /// have A's size (checked). b = 0 gives x = 0, converged. Non-finite values in b, x or along
  /// the iteration stop the solve (no hang) with `converged` false. Never throws.
  virtual LinearSolveStats Solve(const VecX& b, VecX& x) = 0;
  /// Checkpoints: what the solver keeps from one Factorize for later ones besides the matrix
  /// it is given (a preconditioner built from an earlier matrix, kept while it works), so that
  /// a restored run solves with the same one. RestoreState is called after the matrix `current`
  /// (the last one given to Factorize, or one a Factorize will replace) has its values back.
  /// Default: nothing to save (the serial solvers; their lagged preconditioners are rebuilt
  /// on resume, docs/robustness.md).
  virtual void SaveState(StateWriter& /*out*/) const {}
  virtual void RestoreState(StateReader& /*in*/, const SparseMatrix& /*current*/) {}
};

/// The 6 rigid-body modes (3 translations, 3 rotations about the centroid) of nodes at
/// `positions` (3N, node-major): a 3N by 6 matrix, the near-null space of an elasticity
/// stiffness matrix with 3 DOFs per node.
Eigen::MatrixXd RigidBodyModes(const VecX& positions);

/// Builds the solver `options` describe (names as in LinearSolver::name()). Throws InputError
/// for an unknown type or preconditioner (listing the choices), for preconditioner "cholesky"
/// or "amg" with a type other than "cg", and for tolerance ≤ 0, max_iterations < 1 or
/// refactor_iterations < 0. The preconditioner is ignored by the direct types.
std::unique_ptr<LinearSolver> MakeLinearSolver(const LinearSolverOptions& options);

/// Reads {"type", "preconditioner", "tolerance", "max_iterations", "refactor_iterations"} (all
/// optional, defaults as in LinearSolverOptions); throws InputError naming the JSON path for an
/// unknown key, an unknown type/preconditioner (listing the choices), "cholesky" or "amg" with
/// a type other than "cg", a non-positive tolerance or an out-of-range iteration count, and for
/// "schur_gmres" unless `saddle_point` (the caller's systems are a MixedSolid's).
LinearSolverOptions ParseLinearSolverOptions(const JsonNode& node, bool saddle_point = false);

}  // namespace gipsi
GIPSI_EXPORT_END
