/// @file
/// MassSpring checkpoints and snapshots. The state is MassSpringState (mass_spring.h): the
/// explicit integrators are one-step methods whose buffers are rewritten every step, so it is
/// [q; v], the external force and active tension fields, the fibres, and the cavities' pressures
/// and blood compliance estimates (the coupled solve's starting point). Positions, the springs'
/// active weights (from the fibres) and whether any tension acts are rebuilt from it.

#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {

void MassSpring::SaveObjectState(StateWriter& out) const {
  out.BeginSection("MassSpringState", 1);
  WriteFields(out, state_);
  out.EndSection();
}

void MassSpring::RestoreObjectState(StateReader& in) {
  MassSpringState read = state_;  // all or nothing: the object is untouched if the read fails
  in.BeginSection("MassSpringState", 1);
  ReadFields(in, read);
  in.EndSection();
  const bool fibres_changed = read.fibres.get() != state_.fibres.get();
  CopyFields(state_, read);  // into the existing storage: views of it stay valid
  UpdateDerived(fibres_changed);
}

std::unique_ptr<ObjectState> MassSpring::NewObjectState() const {
  return std::make_unique<StateBox<MassSpringState>>(state_);
}

void MassSpring::CopyObjectState(ObjectState& into) const {
  CopyFields(StateBox<MassSpringState>::Of(into).value, state_);
}

void MassSpring::SetObjectState(const ObjectState& from) {
  const std::uint64_t fibres = state_.fibres.stamp();
  CopyFields(state_, StateBox<MassSpringState>::Of(from).value);
  UpdateDerived(state_.fibres.stamp() != fibres);
}

void MassSpring::UpdateDerived(bool fibres_changed) {
  any_active_ = (state_.nodal_active_tension.array() != 0).any();
  if (fibres_changed) UpdateActiveWeights();
  positions_ = Eigen::Map<const Points>(state_.x.data(), 3, num_nodes());
}

}  // namespace gipsi
