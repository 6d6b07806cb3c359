/// @file
/// FemSolid checkpoints: the time scheme (displacements, velocities, accelerations and BDF2
/// history), the previous step's loads (interpolated within load steps), the fields written from
/// outside (external force, active tension, fibres, cavity pressures), the Newton warm start and
/// kept factorisation (newton_state.cc), the cavities' pressure–volume stiffness (the first
/// pressure bracket and the low-rank tangent of a Solve that reuses the factorisation) and the
/// last Jacobian norm (it sets the round-off floor of the next step's first residual).
/// Constraint targets and the current loads are gathered afresh at the start of every step.

#include <algorithm>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/state.h"
#include "gipsi/models/fem/fem_solid.h"

namespace gipsi {
namespace {

// The last Newton statistics (the failure message and the profile read them), field by field:
// a raw copy of the struct would also store its padding bytes, which are indeterminate.
void SaveStats(StateWriter& out, const NewtonStats& s) {
  out.BeginSection("NewtonStats", 1);
  for (bool b :
       {s.converged, s.inadmissible, s.linear_failure, s.interrupted, s.switched_to_indefinite})
    out.WriteBool(b);
  out.WriteInt(static_cast<std::int64_t>(s.linear_failure_kind));
  for (int n : {s.iterations, s.linear_iterations, s.refactorizations, s.monotonicity_accepts,
                s.backtracks})
    out.WriteInt(n);
  out.WriteDouble(s.initial_residual);
  out.WriteDouble(s.final_residual);
  out.WriteArray(std::span<const double>(s.residual_history));
  out.EndSection();
}

NewtonStats RestoreStats(StateReader& in) {
  NewtonStats s;
  in.BeginSection("NewtonStats", 1);
  for (bool* b : {&s.converged, &s.inadmissible, &s.linear_failure, &s.interrupted,
                  &s.switched_to_indefinite})
    *b = in.ReadBool();
  const std::int64_t kind = in.ReadInt();
  if (kind < 0 || kind > static_cast<std::int64_t>(LinearFailure::kNotConverged))
    in.Fail(fmt::format("the Newton statistics: no linear failure kind {}", kind));
  s.linear_failure_kind = static_cast<LinearFailure>(kind);
  for (int* n : {&s.iterations, &s.linear_iterations, &s.refactorizations, &s.monotonicity_accepts,
                 &s.backtracks})
    *n = static_cast<int>(in.ReadInt());
  s.initial_residual = in.ReadDouble();
  s.final_residual = in.ReadDouble();
  std::vector<double> history(s.residual_history.size());
  in.ReadArrayExact(history, "the Newton residual history");
  std::copy(history.begin(), history.end(), s.residual_history.begin());
  in.EndSection();
  return s;
}

}  // namespace

void FemSolid::SaveObjectState(StateWriter& out) const {
  scheme_.SaveState(out);
  newton_->SaveState(out, jac_);
  out.WriteMatrix(f_nodal_prev_);
  out.WriteMatrix(pressure_prev_);
  out.WriteMatrix(traction_prev_);
  out.WriteBool(have_prev_loads_);
  out.WriteMatrix(external_force_);
  out.WriteMatrix(active_tension_);
  out.WriteMatrix(nodal_active_tension_);
  out.WriteBool(active_from_nodes_);
  out.WriteArray(
      std::span<const double>(axes_.empty() ? nullptr : axes_.front().data(), 9 * axes_.size()));
  std::vector<double> cavity_pressures, cavity_stiffnesses;
  for (const Cavity& c : cavities_) {
    cavity_pressures.push_back(c.pressure);
    cavity_stiffnesses.push_back(c.stiffness);
  }
  out.WriteArray(cavity_pressures);
  out.WriteArray(cavity_stiffnesses);
  out.WriteDouble(jacobian_norm_);
  SaveStats(out, last_newton_);
}

void FemSolid::RestoreObjectState(StateReader& in) {
  scheme_.RestoreState(in);
  newton_->RestoreState(in, jac_);
  in.ReadMatrixExact(f_nodal_prev_, "the previous nodal loads");
  in.ReadMatrixExact(pressure_prev_, "the previous pressures");
  in.ReadMatrixExact(traction_prev_, "the previous tractions");
  have_prev_loads_ = in.ReadBool();
  in.ReadMatrixExact(external_force_, "the external force field");
  in.ReadMatrixExact(active_tension_, "the active tension");
  in.ReadMatrixExact(nodal_active_tension_, "the nodal active tension");
  active_from_nodes_ = in.ReadBool();
  std::vector<double> axes(9 * axes_.size());
  in.ReadArrayExact(axes, "the material axes");
  for (std::size_t e = 0; e < axes_.size(); ++e)
    axes_[e] = Eigen::Map<const Mat3>(axes.data() + 9 * e);
  std::vector<double> cavity_pressures(cavities_.size()), cavity_stiffnesses(cavities_.size());
  in.ReadArrayExact(cavity_pressures, "the cavity pressures");
  in.ReadArrayExact(cavity_stiffnesses, "the cavity stiffnesses");
  for (std::size_t c = 0; c < cavities_.size(); ++c) {
    cavities_[c].pressure = cavity_pressures[c];
    cavities_[c].stiffness = cavity_stiffnesses[c];
  }
  jacobian_norm_ = in.ReadDouble();
  last_newton_ = RestoreStats(in);
  UpdatePositions();
}

}  // namespace gipsi
