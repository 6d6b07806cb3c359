/// @file
/// FemSolid checkpoints and snapshots. The state is FemState (fem_state.h): the time scheme
/// (displacements, velocities, accelerations and BDF2 history), the previous step's loads
/// (interpolated within load steps), the fields written from outside (external force, active
/// tension, fibres, cavity pressures), the cavities' pressure–volume stiffness (the first
/// pressure bracket and the low-rank tangent of a Solve that reuses the factorisation), the last
/// Jacobian norm (it sets the round-off floor of the next step's first residual) and the last
/// Newton statistics. Constraint targets and the current loads are gathered afresh at the start
/// of every step.
///
/// What the Newton solver hands from one solve to the next (warm start, kept factorisation) is
/// a cache of the future, not state. A checkpoint saves it too (newton_state.cc), because a
/// resumed run must continue bitwise; a snapshot restore drops it (the retry of a failed step
/// factorises afresh), which is the rule docs/architecture.md states.

#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/models/fem/fem_solid.h"

namespace gipsi {

void FemSolid::SaveObjectState(StateWriter& out) const {
  out.BeginSection("FemState", 1);
  WriteFields(out, state_);
  out.EndSection();
  newton_->SaveState(out, jac_);
}

void FemSolid::RestoreObjectState(StateReader& in) {
  FemState read = state_;  // all or nothing: the object is untouched if the read fails
  in.BeginSection("FemState", 1);
  ReadFields(in, read);
  in.EndSection();
  newton_->RestoreState(in, jac_);
  state_ = std::move(read);
  UpdatePositions();
}

std::unique_ptr<ObjectState> FemSolid::NewObjectState() const {
  return std::make_unique<StateBox<FemState>>(state_);
}

void FemSolid::CopyObjectState(ObjectState& into) const {
  CopyFields(StateBox<FemState>::Of(into).value, state_);
}

void FemSolid::SetObjectState(const ObjectState& from) {
  CopyFields(state_, StateBox<FemState>::Of(from).value);
  newton_->ForgetHandOver();
  UpdatePositions();
}

}  // namespace gipsi
