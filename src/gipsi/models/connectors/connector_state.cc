/// @file
/// Checkpoints of the built-in connectors. BoundaryCoupling and FieldCopy only transfer values
/// (their buffers are rewritten by every Fire), so they have no state of their own;
/// ExcitationContraction keeps the tension it integrates over time.

#include "gipsi/base/state.h"
#include "gipsi/models/connectors/boundary_coupling.h"
#include "gipsi/models/connectors/excitation_contraction.h"
#include "gipsi/models/connectors/field_copy.h"

namespace gipsi {

void BoundaryCoupling::SaveConnectorState(StateWriter& /*out*/) const {}
void BoundaryCoupling::RestoreConnectorState(StateReader& /*in*/) {}

void FieldCopy::SaveConnectorState(StateWriter& /*out*/) const {}
void FieldCopy::RestoreConnectorState(StateReader& /*in*/) {}

void ExcitationContraction::SaveConnectorState(StateWriter& out) const {
  out.WriteMatrix(tension_);
  out.WriteDouble(last_time_);
  out.WriteBool(fired_);
}

void ExcitationContraction::RestoreConnectorState(StateReader& in) {
  in.ReadMatrixExact(tension_, "the active tension");
  last_time_ = in.ReadDouble();
  fired_ = in.ReadBool();
}

}  // namespace gipsi
