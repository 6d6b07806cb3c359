#pragma once
/// @file
/// The concrete LinearSolver implementations behind MakeLinearSolver, and checks they share.
/// Internal to the sparse layer: other code goes through MakeLinearSolver.

#include <memory>

#include "gipsi/base/export.h"
#include "gipsi/numerics/sparse/linear_solver.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Preconditioned CG (pcg.cc). `options` must already be validated (type "cg", known
/// preconditioner, tolerance > 0, max_iterations ≥ 1).
std::unique_ptr<LinearSolver> MakePcgSolver(const LinearSolverOptions& options);
/// Eigen SimplicialLDLT (direct_solvers.cc); `options.tolerance` judges `converged`.
std::unique_ptr<LinearSolver> MakeLdltSolver(const LinearSolverOptions& options);
/// CHOLMOD supernodal LLᵀ (direct_solvers.cc); `options.tolerance` judges `converged`.
std::unique_ptr<LinearSolver> MakeCholmodSolver(const LinearSolverOptions& options);

/// UMFPACK sparse LU with partial pivoting (direct_solvers.cc): any nonsingular matrix, e.g.
/// the saddle-point systems of mixed (displacement–pressure) elements; nonsymmetric ones too.
std::unique_ptr<LinearSolver> MakeUmfpackSolver(const LinearSolverOptions& options);

/// True if every stored value of A is finite.
bool AllValuesFinite(const SparseMatrix& A);

/// Aborts (GIPSI_CHECK) unless A is square, compressed, and has `rows` rows and `nonzeros`
/// stored entries, i.e. plausibly the pattern that was analysed (a cheap check; the full
/// pattern is not compared). `who` names the caller in the message.
void CheckAnalysedShape(const SparseMatrix& A, Index rows, Index nonzeros, const char* who);

}  // namespace gipsi
GIPSI_EXPORT_END
