/// @file
/// MixedSolid's checkpoint cache. The state is MixedState (mixed_state.h), bound with
/// BindState. What the Newton solver hands from one solve to the next (warm start, kept
/// factorisation) is a cache of the future: a checkpoint saves it too (newton_state.cc),
/// because a resumed run must continue bitwise; a snapshot restore drops it (the retry of a
/// failed step factorises afresh), the rule docs/architecture.md states.

#include "gipsi/models/fem/mixed_solid.h"

namespace gipsi {

void MixedSolid::SaveStateCache(StateWriter& out) const { newton_->SaveState(out, jac_); }

void MixedSolid::RestoreStateCache(StateReader& in) { newton_->RestoreState(in, jac_); }

void MixedSolid::DropStateCache() { newton_->ForgetHandOver(); }

}  // namespace gipsi
