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

#include "gipsi/base/state.h"
#include "gipsi/models/fem/fem_solid.h"

namespace gipsi {

void FemSolid::SaveStateCache(StateWriter& out) const { newton_->SaveState(out, jac_); }

void FemSolid::RestoreStateCache(StateReader& in) { newton_->RestoreState(in, jac_); }

void FemSolid::DropStateCache() { newton_->ForgetHandOver(); }

}  // namespace gipsi
