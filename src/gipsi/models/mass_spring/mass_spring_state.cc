/// @file
/// MassSpring after a restore. The state is MassSpringState (mass_spring.h), bound with
/// BindState: the explicit integrators are one-step methods whose buffers are rewritten every
/// step, so it is [q; v], the external force and active tension fields, the fibres, and the
/// cavities' pressures and blood compliance estimates (the coupled solve's starting point).
/// Positions, the springs' active weights (from the fibres) and whether any tension acts are
/// rebuilt from it.

#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {

void MassSpring::StateRestored() {
  any_active_ = (state_.nodal_active_tension.array() != 0).any();
  // UpdateActiveWeights allocates: only when the fibres differ from those it last used (a
  // checkpoint read always gives them a new stamp; a snapshot keeps theirs).
  if (state_.fibres.stamp() != weights_stamp_) UpdateActiveWeights();
  positions_ = Eigen::Map<const Points>(state_.x.data(), 3, num_nodes());
}

}  // namespace gipsi
