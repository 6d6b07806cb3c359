/// @file
/// MassSpring checkpoints. The explicit integrators are one-step methods whose buffers are
/// rewritten every step, so the state is [q; v] and the external force field.

#include "gipsi/core/state.h"
#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {

void MassSpring::SaveObjectState(StateWriter& out) const {
  out.WriteMatrix(x_);
  out.WriteMatrix(external_force_);
}

void MassSpring::RestoreObjectState(StateReader& in) {
  in.ReadMatrixExact(x_, "the state [q; v]");
  in.ReadMatrixExact(external_force_, "the external force field");
  positions_ = Eigen::Map<const Points>(x_.data(), 3, num_nodes());
}

}  // namespace gipsi
