/// @file
/// FemSolid as an OdeSystem: explicit (or any one-step) time integration of the semi-discrete
/// equations of motion with the lumped mass,
///   u̇ = v,   v̇ = M_L⁻¹ (f_ext(u, s) − f_int(u) − α M_L v − β K(u) v),
/// where s = (t − t_n)/Δt interpolates the loads between the previous step's and this step's
/// (as the implicit schemes do). Rayleigh β damping uses the tangent K(u) at the stage's state,
/// assembled with its forces: the implicit schemes freeze it at the step's start (K_n), which
/// is first-order in Δt and would cap RK4 at first order. Constrained axes move at their prescribed
/// velocity through the step (a displacement target u* gives (u* − u_n)/Δt) and do not accelerate;
/// their end position is then set to the target exactly. Refused: a consistent mass (the ODE needs
/// M⁻¹ cheaply) and cavities coupled to blood (their pressure is solved with the wall, monolithic).
/// Split over processes (FemParams::distribution), the forces and lumped masses are summed at
/// shared nodes, so every process computes the same accelerations there, and the step's verdicts
/// (an inverted element, a non-finite state) are reductions; only explicit integrators (their
/// stages need no norms or solves) are taken.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/models/fem/fem_solid.h"

namespace gipsi {

FemSolid::FemSolid(std::string name, std::shared_ptr<const Mesh> domain, FemParams params,
                   std::unique_ptr<OdeIntegrator> integrator)
    : FemSolid(std::move(name), std::move(domain), std::move(params)) {
  GIPSI_CHECK(integrator != nullptr);
  if (dist_ && !integrator->is_explicit())
    throw InputError(fmt::format(
        "object '{}': a FemSolid split over MPI ranks does not take the implicit ODE integrator "
        "'{}' (its solves are not distributed): use an explicit integrator or an implicit scheme "
        "(\"Static\", \"BackwardEuler\", \"BDF2\", \"Newmark\"; docs/scale-out.md)",
        this->path(), integrator->name()));
  if (!params_.lumped_mass)
    throw InputError(fmt::format(
        "object '{}': integrator '{}' steps the equations of motion as an ODE, which needs the "
        "lumped mass: set \"mass\": \"lumped\" (or use an implicit scheme: \"BackwardEuler\", "
        "\"BDF2\", \"Newmark\")",
        this->path(), integrator->name()));
  ode_integrator_ = std::move(integrator);
  ode_integrator_->Prepare(ode_size());
  ode_y_ = VecX::Zero(ode_size());
  if (dist_) {
    VecX mass(3 * num_nodes());
    for (Index i = 0; i < num_nodes(); ++i) mass.segment<3>(3 * i).setConstant(lumped_mass_[i]);
    dist_->SumShared(mass);
    whole_lumped_mass_.resize(num_nodes());
    for (Index i = 0; i < num_nodes(); ++i) whole_lumped_mass_[i] = mass[3 * i];
  }
}

void FemSolid::CalcDerivative(double t, Eigen::Ref<const VecX> y, Eigen::Ref<VecX> ydot) const {
  const Index n3 = 3 * num_nodes();
  GIPSI_CHECK(y.size() == 2 * n3 && ydot.size() == 2 * n3);
  const double s = ode_dt_ > 0 ? std::clamp((t - ode_t0_) / ode_dt_, 0.0, 1.0) : 1.0;
  ydot.head(n3) = y.tail(n3);
  // With Rayleigh β the tangent at this state comes with the forces (one pass): C(u) v.
  const bool stiffness_damping = params_.rayleigh_stiffness > 0;
  if (!AssembleElements(y.data(), f_int_, stiffness_damping ? damping_k_.valuePtr() : nullptr)) {
    ode_invalid_ = true;
    ydot.tail(n3).setZero();
    return;
  }
  AssembleExternal(y.data(), s);
  f_ext_ -= f_int_;
  if (stiffness_damping) {
    work2_ = y.tail(n3);
    SymmetricSpMV(damping_k_, work2_, work_);
    f_ext_ -= params_.rayleigh_stiffness * work_;
  }
  if (dist_) dist_->SumShared(f_ext_);
  const VecX& mass = dist_ ? whole_lumped_mass_ : lumped_mass_;
  auto acceleration = ydot.tail(n3);
  for (Index i = 0; i < num_nodes(); ++i)
    acceleration.segment<3>(3 * i) =
        f_ext_.segment<3>(3 * i) / mass[i] - params_.rayleigh_mass * y.segment<3>(n3 + 3 * i);
  for (int dof : constrained_dofs_) acceleration[dof] = 0;
}

StepStatus FemSolid::StepOde(double t, double dt) {
  const auto start = std::chrono::steady_clock::now();
  const Index n3 = 3 * num_nodes();
  GatherTargets();
  x_begin_ = state_.scheme.x();
  ode_y_.head(n3) = x_begin_;
  ode_y_.tail(n3) = state_.scheme.v();
  for (int dof : constrained_dofs_)
    ode_y_[n3 + dof] = constraint_[static_cast<std::size_t>(dof)] == 1
                           ? (target_[dof] - x_begin_[dof]) / dt
                           : target_[dof];
  ode_invalid_ = false;
  ode_t0_ = t;
  ode_dt_ = dt;
  const bool solved = ode_integrator_->Step(OdeView(*this), t, dt, ode_y_);
  ode_dt_ = 0;
  profile_.assembly_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ++profile_.steps;
  failure_detail_.clear();
  if (ode_invalid_) {  // the same on every process (AssembleElements' verdict is reduced)
    failure_detail_ = dist_
                          ? fmt::format("{}: tet {} ({}) is outside its law's domain (det F <= 0?)",
                                        ode_integrator_->name(), invalid_id_, domain().TetIdKind())
                          : fmt::format("{}: {} is outside its law's domain (det F <= 0?)",
                                        ode_integrator_->name(), domain().TetName(first_invalid_));
    return StepStatus::Failed("an element inverted in a stage of the step; tet",
                              dist_ ? invalid_id_ : domain().TetId(first_invalid_));
  }
  if (!solved) {
    failure_detail_ = fmt::format("{}: {}", ode_integrator_->name(), ode_integrator_->failure());
    return StepStatus::Failed("the implicit integrator's solve failed (state left at the start)");
  }
  double non_finite = ode_y_.allFinite() ? 0.0 : 1.0;
  if (dist_) dist_->Reduce({&non_finite, 1}, true);  // one process's NaN stops every process
  if (non_finite > 0) return StepStatus::Diverged("non-finite position or velocity");
  for (int dof : constrained_dofs_)
    if (constraint_[static_cast<std::size_t>(dof)] == 1) ode_y_[dof] = target_[dof];
  // The step's mean acceleration, (v_{n+1} − v_n)/Δt: what reaction forces and outputs read.
  work_ = (ode_y_.tail(n3) - state_.scheme.v()) / dt;
  state_.scheme.SetAcceleration(work_);
  work_ = ode_y_.tail(n3);
  state_.scheme.SetVelocity(work_);
  work_ = ode_y_.head(n3);
  state_.scheme.SetPositions(work_);
  UpdatePositions();
  state_.f_nodal_prev = f_nodal_new_;
  state_.pressure_prev = pressure_new_;
  state_.traction_prev = traction_new_;
  return StepStatus::Ok();
}

double FemSolid::stable_dt_estimate() const {
  // Gershgorin: every eigenvalue ω² of M_L⁻¹ K lies below max_i Σ_j |K_ij| / m_i.
  SparseMatrix k = assembly_.MakePattern();
  if (!AssembleElements(VecX::Zero(3 * num_nodes()).eval().data(), f_int_, k.valuePtr())) return 0;
  VecX row_sum = VecX::Zero(k.rows());
  for (Index c = 0; c < k.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(k, c); it; ++it) row_sum[it.row()] += std::abs(it.value());
  // Split: the row sums and masses of shared nodes summed, the bound's maximum over processes.
  if (dist_) dist_->SumShared(row_sum);
  const VecX& mass = dist_ && whole_lumped_mass_.size() > 0 ? whole_lumped_mass_ : lumped_mass_;
  double omega2 = 0;
  for (Index i = 0; i < row_sum.size(); ++i) omega2 = std::max(omega2, row_sum[i] / mass[i / 3]);
  if (dist_) dist_->Reduce({&omega2, 1}, true);
  return omega2 > 0 ? 2.0 / std::sqrt(omega2) : std::numeric_limits<double>::infinity();
}

}  // namespace gipsi
