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

#include <Eigen/SparseCore>

#include "gipsi/base/json_node.h"
#include "gipsi/base/math.h"

namespace gipsi {

/// Square sparse matrix, compressed columns, 32-bit indices. Symmetric matrices store both
/// triangles, so a column is also a row (SpMV can run row-parallel).
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

/// y = A x for a symmetric A stored in full (both triangles); parallel over rows (OpenMP,
/// static schedule: the same bits for the same thread count). Preconditions (checked): sizes
/// match, A is compressed. Allocates nothing.
void SymmetricSpMV(const SparseMatrix& A, const VecX& x, VecX& y);

/// Which solver and how hard it works. Plain struct.
struct LinearSolverOptions {
  /// "cg" (preconditioned conjugate gradients), "ldlt" (Eigen SimplicialLDLT) or "cholmod"
  /// (SuiteSparse CHOLMOD supernodal LLᵀ).
  std::string type = "cg";
  /// For "cg": "none", "jacobi", "ic" (incomplete Cholesky) or "cholesky" (a CHOLMOD
  /// factorisation of an earlier matrix, refreshed only when CG needs more than
  /// `refactor_iterations` iterations with it).
  std::string preconditioner = "ic";
  /// CG stops when ‖b − A x‖ ≤ tolerance · ‖b‖.
  double tolerance = 1e-6;
  int max_iterations = 2000;
  int refactor_iterations = 30;
};

/// What one Solve did. Plain struct.
struct LinearSolveStats {
  bool converged = false;
  int iterations = 0;             ///< CG iterations (0 for direct solvers)
  double relative_residual = 0;   ///< ‖b − A x‖ / ‖b‖ at exit (0 if b = 0)
  bool refactorized = false;      ///< a numeric factorisation happened in the last Factorize
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
  /// Symbolic analysis (ordering, elimination tree) for matrices with A's pattern. Call again
  /// only when the pattern changes.
  virtual void AnalyzePattern(const SparseMatrix& A) = 0;
  /// Numeric set-up for A (same pattern as analysed). Iterative solvers keep a pointer to A:
  /// it must stay alive and unchanged until the next Factorize. Returns false if A is found
  /// not to be positive definite (a failed factorisation); never throws.
  [[nodiscard]] virtual bool Factorize(const SparseMatrix& A) = 0;
  /// Solves A x = b for the last factorised A. On entry x is the initial guess (warm start;
  /// direct solvers ignore it). Never throws; `converged` is false on failure.
  virtual LinearSolveStats Solve(const VecX& b, VecX& x) = 0;
};

/// Builds the solver `options` describe. Throws InputError for an unknown type/preconditioner.
std::unique_ptr<LinearSolver> MakeLinearSolver(const LinearSolverOptions& options);

/// Reads {"type", "preconditioner", "tolerance", "max_iterations", "refactor_iterations"} (all
/// optional, defaults as in LinearSolverOptions); throws InputError naming the JSON path.
LinearSolverOptions ParseLinearSolverOptions(const JsonNode& node);

}  // namespace gipsi
