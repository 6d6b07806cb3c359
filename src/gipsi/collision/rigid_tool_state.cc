/// @file
/// RigidTool checkpoints: the translation and velocity (the rest is the scene's motion law).

#include "gipsi/base/state.h"
#include "gipsi/collision/rigid_tool.h"

namespace gipsi {

void RigidTool::SaveObjectState(StateWriter& out) const {
  out.WriteMatrix(offset_);
  out.WriteMatrix(velocity_);
}

void RigidTool::RestoreObjectState(StateReader& in) {
  in.ReadMatrixExact(offset_, "the tool offset");
  in.ReadMatrixExact(velocity_, "the tool velocity");
  Place();
}

}  // namespace gipsi
