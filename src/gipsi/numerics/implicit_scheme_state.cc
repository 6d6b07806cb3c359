/// @file
/// ImplicitScheme checkpoints: x_n, v_n, a_n and the BDF2 history (x_n − x_{n−1}, v_{n−1}, the
/// previous step size). The per-step coefficients are rebuilt by Begin.

#include "gipsi/base/state.h"
#include "gipsi/numerics/implicit_scheme.h"

namespace gipsi {

void ImplicitScheme::SaveState(StateWriter& out) const {
  out.BeginSection("ImplicitScheme", 1);
  out.WriteString(ToString(kind_));
  out.WriteMatrix(x_);
  out.WriteMatrix(v_);
  out.WriteMatrix(a_);
  out.WriteMatrix(dx_prev_);
  out.WriteMatrix(v_prev_);
  out.WriteDouble(dt_prev_);
  out.WriteDouble(dt_);
  out.WriteBool(bdf2_now_);
  out.EndSection();
}

void ImplicitScheme::RestoreState(StateReader& in) {
  in.BeginSection("ImplicitScheme", 1);
  if (in.ReadString() != ToString(kind_)) in.Fail("the checkpoint has another time scheme");
  in.ReadMatrixExact(x_, "the displacements");
  in.ReadMatrixExact(v_, "the velocities");
  in.ReadMatrix(a_);
  in.ReadMatrix(dx_prev_);
  in.ReadMatrix(v_prev_);
  dt_prev_ = in.ReadDouble();
  dt_ = in.ReadDouble();
  bdf2_now_ = in.ReadBool();
  in.EndSection();
}

}  // namespace gipsi
