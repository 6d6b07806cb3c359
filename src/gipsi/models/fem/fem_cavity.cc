// FemSolid's cavities coupled to blood through a CavityLaw (cavity_law.h).
//
// For each coupled cavity the step's unknowns are the displacements u and the pressure p, with
//   f_int(u) − p ∂V/∂x(u) − … = 0     (the pressure acts as a follower load, p ∂V/∂x)
//   V(u) = V_b(p)                      (the wall encloses what the blood fills at the end)
// where V_b is the law's end volume, non-increasing in p. For given u the second equation has
// one root p(u) (V − V_b is increasing in p), found here by a bracketed secant iteration, so
// Newton sees a residual in u alone. Differentiating p(u): ∂p/∂u = ∂V/∂x / C with
// C = −dV_b/dp > 0 (the blood's compressibility keeps it positive when the valves are closed),
// which adds the rank-one term (1/C) ∂V/∂x ⊗ ∂V/∂x to the tangent, solved by Newton with the
// Sherman–Morrison–Woodbury formula instead of filling the sparse matrix.

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/numerics/bracketed_root.h"

namespace gipsi {
namespace {

/// Root of h(p) = v − law(p) (increasing in p) near `guess`; false if the law fails or no root
/// is bracketed. `stiffness` estimates −dp/dV_b [Pa/m³] (0: unknown) for the first step.
bool SolvePressure(CavityLaw& law, double t, double dt, double v, double guess, double stiffness,
                   double& p) {
  auto h = [&](double q, double& out) {
    double vb = 0;
    if (!law.EndVolume(t, dt, q, vb) || !std::isfinite(vb)) return false;
    out = v - vb;
    return true;
  };
  // Step away from the guess in the direction that reduces |h|.
  auto first_step = [&](double h0) {
    const double first = stiffness > 0 ? std::max(2 * std::abs(h0) * stiffness, 1e-3)
                                       : std::max(1.0, 0.01 * std::abs(guess));
    return h0 > 0 ? -first : first;
  };
  return SolveIncreasingRoot(h, guess, first_step, 1e-13 * std::abs(v), p);
}

}  // namespace

std::vector<std::string> FemSolid::cavity_names() const { return CavityNames(params_.cavities); }

void FemSolid::AttachCavityLaw(std::string_view cavity, CavityLaw* law) {
  GIPSI_CHECK(law != nullptr);
  const std::size_t i =
      FindUncoupledCavity(name(), type_name(), params_.cavities, cavities_, cavity);
  if (ode_integrator_)
    throw InputError(fmt::format(
        "object '{}' (FemSolid): cavity '{}' coupled to blood needs an implicit scheme "
        "(\"integrator\": \"BackwardEuler\", \"BDF2\" or \"Newmark\"), which solves the pressure "
        "with the wall; '{}' cannot",
        path(), cavity, ode_integrator_->name()));
  cavities_[i].law = law;
  cavity_follower_tangent_ = newton_->linear_solver().AcceptIndefinite();
  if (!cavity_follower_tangent_)
    Log().warn(
        "object '{}': cavity '{}' is coupled to blood but the linear solver '{}' needs "
        "positive definite matrices, so the pressure's follower tangent is left out and "
        "Newton converges linearly; \"linear_solver\": {{\"type\": \"cholmod\"}} or "
        "{{\"type\": \"ldlt\"}} keeps it",
        path(), cavity, newton_->linear_solver().name());
}

double FemSolid::CavityPressure(std::size_t i) const {
  GIPSI_CHECK(i < cavities_.size());
  return state_.cavities[i].pressure;
}

bool FemSolid::AddCoupledCavityLoads(const double* u) {
  for (std::size_t c = 0; c < cavities_.size(); ++c) {
    Cavity& cavity = cavities_[c];
    FemCavityState& cs = state_.cavities[c];
    if (cavity.law == nullptr) continue;
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k) {
      const auto node = static_cast<Index>(cavity.nodes[k]);
      cavity.positions.col(static_cast<Index>(k)) =
          rest_.segment<3>(3 * node) + Eigen::Map<const Vec3>(u + 3 * node);
    }
    const double v = cavity.volume.Compute(cavity.positions, &cavity.local_gradient);
    double p = cs.pressure;
    if (!SolvePressure(*cavity.law, step_time_, step_dt_, v, cs.pressure, cs.stiffness, p)) {
      failed_cavity_ = static_cast<int>(c);
      return false;
    }
    cs.pressure = p;
    cavity.gradient.setZero();
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k) {
      const auto node = static_cast<Index>(cavity.nodes[k]);
      cavity.gradient.segment<3>(3 * node) += cavity.local_gradient.col(static_cast<Index>(k));
    }
    for (int dof : constrained_dofs_) cavity.gradient[dof] = 0;
    f_ext_ += p * cavity.gradient;
  }
  return true;
}

void FemSolid::AddCoupledCavityTangent(const double* u, double* jv) {
  for (std::size_t c = 0; c < cavities_.size(); ++c) {
    const Cavity& cavity = cavities_[c];
    FemCavityState& cs = state_.cavities[c];
    if (cavity.law == nullptr) continue;
    // The follower part p ∂²V/∂x² is the faces' pressure tangent (the cap of an open rim moves
    // only with the rim; its curvature terms are left out, exact when the rim is held). It can
    // make the sparse part indefinite (the rank-one term restores definiteness), so it is left
    // out for solvers that need SPD matrices: Newton then converges linearly.
    if (cavity_follower_tangent_)
      for (int f : cavity.faces) AddFaceLoadTangent(f, u, cs.pressure, Vec3::Zero(), jv);
    // C = −dV_b/dp by a one-sided difference of 1e-6 of the pressure (at least 1 mPa).
    const double p = cs.pressure;
    const double dp = std::max(1e-3, 1e-6 * std::abs(p));
    double v0 = 0, v1 = 0;
    cs.stiffness = 0;
    if (cavity.law->EndVolume(step_time_, step_dt_, p, v0) &&
        cavity.law->EndVolume(step_time_, step_dt_, p + dp, v1) && v0 > v1)
      cs.stiffness = dp / (v0 - v1);
  }
}

void FemSolid::AddCoupledCavityForces(VecX& f) const {
  for (std::size_t c = 0; c < cavities_.size(); ++c) {
    const Cavity& cavity = cavities_[c];
    if (cavity.law == nullptr) continue;
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k)
      cavity.positions.col(static_cast<Index>(k)) = positions_.col(cavity.nodes[k]);
    cavity.volume.Compute(cavity.positions, &cavity.local_gradient);
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k)
      f.segment<3>(3 * static_cast<Index>(cavity.nodes[k])) +=
          state_.cavities[c].pressure * cavity.local_gradient.col(static_cast<Index>(k));
  }
}

void FemSolid::RestoreCavityPressures() {
  for (std::size_t c = 0; c < cavities_.size(); ++c)
    if (cavities_[c].law != nullptr) state_.cavities[c].pressure = cavities_[c].pressure_begin;
}

int FemSolid::num_low_rank_terms() const {
  int count = 0;
  for (const Cavity& cavity : cavities_) count += cavity.law != nullptr ? 1 : 0;
  return count;
}

void FemSolid::LowRankTerm(int k, const VecX*& b, double& w) const {
  for (std::size_t c = 0; c < cavities_.size(); ++c) {
    if (cavities_[c].law == nullptr) continue;
    if (k-- == 0) {
      b = &cavities_[c].gradient;
      w = state_.cavities[c].stiffness;
      return;
    }
  }
  GIPSI_CHECK(false);
}

}  // namespace gipsi
