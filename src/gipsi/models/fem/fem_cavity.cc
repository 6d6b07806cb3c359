// FemSolid's cavities coupled to blood through a CavityLaw (cavity_law.h).
//
// For each coupled cavity the step's unknowns are the displacements u and the pressure p, with
//   r_u = f_int(u) − p ∂V/∂x(u) − … = 0   (the pressure acts as a follower load, p ∂V/∂x)
//   r_p = V(u) − V_b(p) = 0               (the wall encloses what the blood fills at the end)
// where V_b is the law's end volume, non-increasing in p. Newton solves for (u, p) together:
// p is a bordered unknown (NonlinearSystem::num_bordered) with ∂r_p/∂p = C = −dV_b/dp > 0 (the
// blood's compressibility keeps it positive when the valves are closed). Eliminating Δp adds
// the rank-one term (1/C) ∂V/∂x ⊗ ∂V/∂x to the tangent, solved by Newton with the
// Sherman–Morrison–Woodbury formula instead of filling the sparse matrix.
//
// Solving p(u) from r_p = 0 inside the residual instead (as this file did until stop 38) makes
// the coupling a penalty of weight 1/C: with the valves closed (C of a few 1e-12 m³/Pa) the
// quadratic volume error of every Newton step reappears in r_u multiplied by 1/C, the line
// search cuts the steps, and Newton needed 6–13 iterations with several factorisations at each
// isovolumetric phase of the heart. As a bordered unknown p absorbs that error linearly.

#include <cmath>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/models/fem/fem_solid.h"

namespace gipsi {
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
  // Newton's iterate gains the cavity's pressure.
  bordered_ = num_low_rank_terms();
  const Index n = jac_.rows();
  newton_x_.setZero(n + bordered_);
  bordered_d_.setZero(n);
  bordered_r_.setZero(n);
  newton_->Prepare(jac_, bordered_);
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
    CavityPositions(cavity, u);
    const double v = cavity.volume.Compute(cavity.positions, &cavity.local_gradient);
    const double p = cs.pressure;  // the iterate's (FemSolid::Increment sets it)
    double vb = 0;
    if (!cavity.law->EndVolume(step_time_, step_dt_, p, vb) || !std::isfinite(vb)) {
      failed_cavity_ = static_cast<int>(c);
      return false;
    }
    cavity.volume_residual = v - vb;
    // Evaluated with every residual (two law evaluations): the Woodbury solve and the
    // elimination of Δp then use the stiffness at the current pressure even while a
    // factorisation of an older tangent is kept, e.g. when a valve has just closed.
    cs.stiffness = CavityLawStiffness(*cavity.law, step_time_, step_dt_, p, vb);
    if (!(cs.stiffness > 0)) {  // p would not be determined by the volume
      failed_cavity_ = static_cast<int>(c);
      return false;
    }
    cavity.gradient.setZero();
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k) {
      const int node = CavityNode(cavity, k);
      if (node >= 0)
        cavity.gradient.segment<3>(3 * node) += cavity.local_gradient.col(static_cast<Index>(k));
    }
    for (int dof : constrained_dofs_) cavity.gradient[dof] = 0;
    if (!dist_) {
      f_ext_ += p * cavity.gradient;
    } else {  // the whole gradient at every local node: its load counts on the owner alone
      const Index owned = dist_->owned();
      f_ext_.head(owned) += p * cavity.gradient.head(owned);
    }
  }
  return true;
}

void FemSolid::AddCoupledCavityTangent(const double* u, double* jv) {
  for (std::size_t c = 0; c < cavities_.size(); ++c) {
    const Cavity& cavity = cavities_[c];
    const FemCavityState& cs = state_.cavities[c];
    if (cavity.law == nullptr) continue;
    // The follower part p ∂²V/∂x² is the faces' pressure tangent (the cap of an open rim moves
    // only with the rim; its curvature terms are left out, exact when the rim is held). It can
    // make the sparse part indefinite (the rank-one term restores definiteness), so it is left
    // out for solvers that need SPD matrices: Newton then converges linearly.
    if (cavity_follower_tangent_)
      for (int f : cavity.faces) AddFaceLoadTangent(f, u, cs.pressure, Vec3::Zero(), jv);
    // The rank-one weight cs.stiffness was set with the residual (AddCoupledCavityLoads).
  }
}

void FemSolid::AddCoupledCavityForces(VecX& f) const {
  for (std::size_t c = 0; c < cavities_.size(); ++c) {
    const Cavity& cavity = cavities_[c];
    if (cavity.law == nullptr) continue;
    if (dist_) {
      CavityPositions(cavity, u().data());
    } else {
      for (std::size_t k = 0; k < cavity.nodes.size(); ++k)
        cavity.positions.col(static_cast<Index>(k)) = positions_.col(cavity.nodes[k]);
    }
    cavity.volume.Compute(cavity.positions, &cavity.local_gradient);
    // (Distributed: on owned nodes, the forces being summed over the processes after.)
    const Index owned = dist_ ? dist_->num_owned_nodes() : num_nodes();
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k)
      if (const int node = CavityNode(cavity, k); node >= 0 && node < owned)
        f.segment<3>(3 * static_cast<Index>(node)) +=
            state_.cavities[c].pressure * cavity.local_gradient.col(static_cast<Index>(k));
  }
}

void FemSolid::CavityPositions(const Cavity& cavity, const double* u) const {
  if (!dist_) {
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k) {
      const auto node = static_cast<Index>(cavity.nodes[k]);
      cavity.positions.col(static_cast<Index>(k)) =
          rest_.segment<3>(3 * node) + Eigen::Map<const Vec3>(u + 3 * node);
    }
    return;
  }
  // The same rest positions and gathered displacements on every process: the same volume.
  cavity.gather->Gather(u, cavity_u_);
  const Points& whole = dist_->whole_mesh().nodes;
  for (std::size_t k = 0; k < cavity.nodes.size(); ++k)
    cavity.positions.col(static_cast<Index>(k)) =
        whole.col(cavity.nodes[k]) + cavity_u_.col(static_cast<Index>(k));
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
