/// @file
/// NewtonSolver checkpoints: the warm start of the next Solve's first linear solve (it changes
/// the iterates of iterative linear solvers), and with reuse_factorization the factorisation
/// kept for the next Solve, saved as the values of the matrix that was factorised and
/// factorised again on restore. Bitwise continuation needs both.
///
/// The factorised values are those of J: while a factorisation is kept (factor_valid_), Solve
/// only writes J in CalcResidualAndJacobian right before factorising it, except when it gives up
/// after max_iterations (then J is newer than the factors). A step whose Newton solve gave up
/// and was bisected can therefore keep factors J no longer holds; a checkpoint right after such
/// a step restores the newer J's factors instead (the run stays correct, its iterates differ in
/// round-off). A step that converged at once never does this.

#include <algorithm>
#include <span>
#include <vector>

#include "gipsi/core/state.h"
#include "gipsi/numerics/newton.h"

namespace gipsi {

void NewtonSolver::SaveState(StateWriter& out, const SparseMatrix& J) const {
  out.BeginSection("NewtonSolver", 2);
  out.WriteBool(warm_valid_);
  out.WriteMatrix(warm_);
  const bool keep = options_.reuse_factorization && factor_valid_;
  out.WriteBool(keep);
  if (keep)
    out.WriteArray(std::span<const double>(J.valuePtr(), static_cast<std::size_t>(J.nonZeros())));
  out.EndSection();
}

void NewtonSolver::RestoreState(StateReader& in, SparseMatrix& J) {
  in.BeginSection("NewtonSolver", 2);
  warm_valid_ = in.ReadBool();
  in.ReadMatrix(warm_);
  factor_valid_ = false;
  if (in.ReadBool()) {
    if (!options_.reuse_factorization)
      in.Fail("the checkpoint keeps a Newton factorisation but this scene does not reuse them");
    std::vector<double> values(static_cast<std::size_t>(J.nonZeros()));
    in.ReadArrayExact(values, "the factorised Newton matrix");
    std::copy(values.begin(), values.end(), J.valuePtr());
    if (!linear_->Factorize(J)) in.Fail("the saved Newton matrix cannot be factorised again");
    factor_valid_ = true;
  }
  in.EndSection();
}

}  // namespace gipsi
