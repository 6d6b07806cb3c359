/// @file
/// EpTissue checkpoints (Monodomain and GridMonodomain): every cell state variable of every
/// node and the activation/APD tracking. The stimuli and clamps are functions of time, the
/// cell models are immutable and the diffusion solve starts from the current voltage, so
/// nothing else carries over between steps. The diffusion matrix is refactorised at the first
/// step after a restore (it depends on the step size only), which gives the same factors.

#include "gipsi/base/state.h"
#include "gipsi/models/ep/ep_tissue.h"

namespace gipsi {

void EpTissue::SaveObjectState(StateWriter& out) const {
  const Index n = num_nodes();
  out.WriteInt(states_->num_states());
  for (int k = 0; k < states_->num_states(); ++k)
    out.WriteMatrix(Eigen::Map<const VecX>(states_->var(k), n));
  out.WriteMatrix(activation_time_);
  out.WriteMatrix(last_activation_);
  out.WriteMatrix(apd_);
  out.WriteMatrix(v_min_);
  out.WriteMatrix(v_peak_);
  out.WriteArray(depolarised_);
  out.WriteInt(last_iterations_);
}

void EpTissue::RestoreObjectState(StateReader& in) {
  const Index n = num_nodes();
  if (in.ReadInt() != states_->num_states())
    in.Fail("the cell model has a different number of state variables in the checkpoint");
  VecX values(n);
  for (int k = 0; k < states_->num_states(); ++k) {
    in.ReadMatrixExact(values, "a cell state variable");
    Eigen::Map<VecX>(states_->var(k), n) = values;
  }
  in.ReadMatrixExact(activation_time_, "the activation times");
  in.ReadMatrixExact(last_activation_, "the last activation times");
  in.ReadMatrixExact(apd_, "the APDs");
  in.ReadMatrixExact(v_min_, "the voltage minima");
  in.ReadMatrixExact(v_peak_, "the voltage peaks");
  in.ReadArrayExact(depolarised_, "the depolarisation flags");
  last_iterations_ = static_cast<int>(in.ReadInt());
  v_prev_ = voltage();
  system_dt_ = -1;  // refactorise at the next step
}

}  // namespace gipsi
