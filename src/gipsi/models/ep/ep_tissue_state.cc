/// @file
/// EpTissue after a restore (Monodomain and GridMonodomain): the state is EpState (every cell
/// state variable of every node and the activation/APD tracking), bound with BindState, so
/// checkpoints and snapshots need no code here beyond what derives from the state.

#include "gipsi/models/ep/ep_tissue.h"

namespace gipsi {

void EpTissue::StateRestored() { v_prev_ = voltage(); }

}  // namespace gipsi
