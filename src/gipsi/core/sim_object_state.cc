/// @file
/// SimObject checkpoints: the base-class part (clock, step count, applied boundary conditions)
/// and the default hooks.

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/core/sim_object.h"

namespace gipsi {

void SimObject::SaveState(StateWriter& out) const {
  out.BeginSection("SimObject", 1);
  out.WriteString(name_);
  out.WriteString(type_name());
  out.WriteDouble(time_);
  out.WriteInt(step_count_);
  // Applied boundary conditions (scene and events); coupling loads are cleared by then.
  const Index nv = bcs_.num_vertices(), nf = bcs_.num_faces();
  std::vector<std::uint8_t> kinds(static_cast<std::size_t>(3 * nv));
  Points values(3, nv), forces(3, nv), tractions(3, nf);
  VecX pressures(nf);
  for (Index v = 0; v < nv; ++v) {
    for (int a = 0; a < 3; ++a)
      kinds[static_cast<std::size_t>(3 * v + a)] = static_cast<std::uint8_t>(bcs_.kind(v, a));
    values.col(v) = bcs_.value(v);
    forces.col(v) = bcs_.force(v);
  }
  for (Index f = 0; f < nf; ++f) {
    tractions.col(f) = bcs_.traction(f);
    pressures[f] = bcs_.pressure(f);
  }
  out.WriteArray(kinds);
  out.WriteMatrix(values);
  out.WriteMatrix(forces);
  out.WriteMatrix(tractions);
  out.WriteMatrix(pressures);
  out.BeginSection(type_name(), 1);
  SaveObjectState(out);
  out.EndSection();
  out.EndSection();
}

void SimObject::RestoreState(StateReader& in) {
  in.BeginSection("SimObject", 1);
  const std::string name = in.ReadString();
  const std::string type = in.ReadString();
  if (name != name_ || type != type_name())
    in.Fail(fmt::format("the checkpoint has object '{}' ({}) where this scene has '{}' ({})", name,
                        type, name_, type_name()));
  const double time = in.ReadDouble();
  const std::int64_t steps = in.ReadInt();
  const Index nv = bcs_.num_vertices(), nf = bcs_.num_faces();
  std::vector<std::uint8_t> kinds(static_cast<std::size_t>(3 * nv));
  Points values(3, nv), forces(3, nv), tractions(3, nf);
  VecX pressures(nf);
  in.ReadArrayExact(kinds, "the boundary constraints of '" + name_ + "'");
  in.ReadMatrixExact(values, "the boundary values");
  in.ReadMatrixExact(forces, "the boundary forces");
  in.ReadMatrixExact(tractions, "the boundary tractions");
  in.ReadMatrixExact(pressures, "the boundary pressures");
  bcs_.ClearCouplingLoads();
  for (Index v = 0; v < nv; ++v) {
    bcs_.Release(v);
    for (int a = 0; a < 3; ++a) {
      const auto kind = static_cast<ConstraintKind>(kinds[static_cast<std::size_t>(3 * v + a)]);
      const auto mask = static_cast<AxisMask>(1 << a);
      if (kind == ConstraintKind::kDisplacement)
        bcs_.PrescribeDisplacement(v, values.col(v), mask);
      else if (kind == ConstraintKind::kVelocity)
        bcs_.PrescribeVelocity(v, values.col(v), mask);
      else if (kind != ConstraintKind::kFree)
        in.Fail("corrupted boundary constraint kind");
    }
    bcs_.SetForce(v, forces.col(v));
  }
  for (Index f = 0; f < nf; ++f) {
    bcs_.SetTraction(f, tractions.col(f));
    bcs_.SetPressure(f, pressures[f]);
  }
  in.BeginSection(type_name(), 1);
  RestoreObjectState(in);
  in.EndSection();
  in.EndSection();
  time_ = time;
  step_count_ = steps;
}

void SimObject::SaveObjectState(StateWriter& /*out*/) const {
  throw InputError(
      fmt::format("object '{}': object type {} does not support checkpoints", name_, type_name()));
}

void SimObject::RestoreObjectState(StateReader& /*in*/) {
  throw InputError(
      fmt::format("object '{}': object type {} does not support checkpoints", name_, type_name()));
}

}  // namespace gipsi
