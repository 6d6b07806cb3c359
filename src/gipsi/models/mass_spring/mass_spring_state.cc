/// @file
/// MassSpring checkpoints. The explicit integrators are one-step methods whose buffers are
/// rewritten every step, so the state is [q; v], the external force and active tension fields,
/// the fibres, and the cavities' pressures and blood compliance estimates (the coupled solve's
/// starting point).

#include <vector>

#include "gipsi/base/state.h"
#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {

void MassSpring::SaveObjectState(StateWriter& out) const {
  out.WriteMatrix(x_);
  out.WriteMatrix(external_force_);
  out.WriteMatrix(nodal_active_tension_);
  out.WriteMatrix(fibres_);
  std::vector<double> cavity_state;
  for (const Cavity& c : cavities_)
    cavity_state.insert(cavity_state.end(), {c.pressure, c.compliance});
  out.WriteArray(cavity_state);
}

void MassSpring::RestoreObjectState(StateReader& in) {
  in.ReadMatrixExact(x_, "the state [q; v]");
  in.ReadMatrixExact(external_force_, "the external force field");
  in.ReadMatrixExact(nodal_active_tension_, "the nodal active tension");
  any_active_ = (nodal_active_tension_.array() != 0).any();
  Points fibres = fibres_;
  in.ReadMatrixExact(fibres, "the fibres");
  if (fibres != fibres_) {
    fibres_ = fibres;
    UpdateActiveWeights();
  }
  std::vector<double> cavity_state(2 * cavities_.size());
  in.ReadArrayExact(cavity_state, "the cavity pressures");
  for (std::size_t c = 0; c < cavities_.size(); ++c) {
    cavities_[c].pressure = cavity_state[2 * c];
    cavities_[c].compliance = cavity_state[2 * c + 1];
  }
  positions_ = Eigen::Map<const Points>(x_.data(), 3, num_nodes());
}

}  // namespace gipsi
