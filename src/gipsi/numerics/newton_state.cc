/// @file
/// NewtonSolver checkpoints: the warm start of the next Solve's first linear solve (it changes
/// the iterates of iterative linear solvers, so bitwise continuation needs it).

#include "gipsi/core/state.h"
#include "gipsi/numerics/newton.h"

namespace gipsi {

void NewtonSolver::SaveState(StateWriter& out) const {
  out.BeginSection("NewtonSolver", 1);
  out.WriteBool(warm_valid_);
  out.WriteMatrix(warm_);
  out.EndSection();
}

void NewtonSolver::RestoreState(StateReader& in) {
  in.BeginSection("NewtonSolver", 1);
  warm_valid_ = in.ReadBool();
  in.ReadMatrix(warm_);
  in.EndSection();
}

}  // namespace gipsi
