/// @file
/// EpTissue checkpoints and snapshots (Monodomain and GridMonodomain): the state is EpState
/// (every cell state variable of every node and the activation/APD tracking). The diffusion
/// matrix is a cache of the step size: a checkpoint restore refactorises it at the next step
/// (which gives the same factors); a snapshot restore keeps it.

#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/models/ep/ep_tissue.h"

namespace gipsi {

void EpTissue::SaveObjectState(StateWriter& out) const {
  out.BeginSection("EpState", 1);
  WriteFields(out, state_);
  out.EndSection();
}

void EpTissue::RestoreObjectState(StateReader& in) {
  EpState read = state_;  // all or nothing: the object is untouched if the read fails
  in.BeginSection("EpState", 1);
  ReadFields(in, read);
  in.EndSection();
  state_ = std::move(read);
  v_prev_ = voltage();
  system_dt_ = -1;  // refactorise at the next step
}

std::unique_ptr<ObjectState> EpTissue::NewObjectState() const {
  return std::make_unique<StateBox<EpState>>(state_);
}

void EpTissue::CopyObjectState(ObjectState& into) const {
  CopyFields(StateBox<EpState>::Of(into).value, state_);
}

void EpTissue::SetObjectState(const ObjectState& from) {
  CopyFields(state_, StateBox<EpState>::Of(from).value);
  v_prev_ = voltage();
}

}  // namespace gipsi
