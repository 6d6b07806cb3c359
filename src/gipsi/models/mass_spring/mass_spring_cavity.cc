// MassSpring's cavities: volume, follower pressure p ∂V/∂x, and the step solved together with a
// blood law (cavity_law.h). The equations are in mass_spring.h.

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/models/mass_spring/mass_spring.h"
#include "gipsi/numerics/bracketed_root.h"

namespace gipsi {

void MassSpring::SetUpCavities() {
  for (WallCavity& wall : MakeWallCavities(
           name(), params_.cavities, domain(), boundary(),
           [this](FieldInfo info) { return DeclareField(std::move(info)); },
           "pressure in the cavity, the follower load p dV/dx on its nodes (solved if coupled)"))
    cavities_.emplace_back(std::move(wall));
  state_.cavities.resize(cavities_.size());
}

double MassSpring::CavityVolume(std::size_t i) const {
  GIPSI_CHECK(i < cavities_.size());
  return cavities_[i].Volume(positions_);
}

double MassSpring::CavityPressure(std::size_t i) const {
  GIPSI_CHECK(i < cavities_.size());
  return state_.cavities[i].pressure;
}

std::vector<std::string> MassSpring::cavity_names() const { return CavityNames(params_.cavities); }

void MassSpring::AttachCavityLaw(std::string_view cavity, CavityLaw* law) {
  GIPSI_CHECK(law != nullptr);
  const std::size_t i =
      FindUncoupledCavity(name(), type_name(), params_.cavities, cavities_, cavity);
  if (!symplectic_)
    throw InputError(
        fmt::format("object '{}' (MassSpring): a cavity coupled to blood needs \"integrator\": "
                    "\"SymplecticEuler\" (its end positions are affine in the pressure), not '{}'",
                    path(), integrator_->name()));
  for (const Cavity& other : cavities_) {
    if (other.law == nullptr) continue;
    for (int node : cavities_[i].nodes)
      if (std::find(other.nodes.begin(), other.nodes.end(), node) != other.nodes.end())
        throw InputError(fmt::format(
            "object '{}': cavity '{}' shares node {} with another cavity coupled to blood; "
            "coupled cavities must be disjoint",
            path(), cavity, node));
  }
  cavities_[i].law = law;
}

void MassSpring::AddCavityForces(Eigen::Ref<const VecX> q, Eigen::Ref<VecX> f,
                                 bool include_coupled) const {
  for (std::size_t c = 0; c < cavities_.size(); ++c) {
    const Cavity& cavity = cavities_[c];
    const double pressure = state_.cavities[c].pressure;
    if ((cavity.law != nullptr && !include_coupled) || pressure == 0) continue;
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k)
      cavity.positions.col(static_cast<Index>(k)) = q.segment<3>(3 * cavity.nodes[k]);
    cavity.volume.Compute(cavity.positions, &cavity.local_gradient);
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k)
      f.segment<3>(3 * cavity.nodes[k]) +=
          pressure * cavity.local_gradient.col(static_cast<Index>(k));
  }
}

void MassSpring::BeginCoupledStep() {
  const BoundaryConditions& bcs = boundary_conditions();
  const auto& v2n = boundary().vertex_to_node;
  for (Cavity& cavity : cavities_) {
    if (cavity.law == nullptr) continue;
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k)
      cavity.positions.col(static_cast<Index>(k)) = state_.x.segment<3>(3 * cavity.nodes[k]);
    cavity.volume.Compute(cavity.positions, &cavity.step_gradient);
    // Held axes do not accelerate (CalcDerivative): the pressure cannot move them either. Cavity
    // nodes are boundary vertices; v2n is sorted, so find each one's vertex by bisection.
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k) {
      const auto it = std::lower_bound(v2n.begin(), v2n.end(), cavity.nodes[k]);
      const auto j = static_cast<Index>(it - v2n.begin());
      for (int a = 0; a < 3; ++a)
        if (bcs.kind(j, a) != ConstraintKind::kFree)
          cavity.step_gradient(a, static_cast<Index>(k)) = 0;
    }
  }
}

bool MassSpring::SolveCoupledCavities(double t, double dt) {
  const Index n = num_nodes();
  for (std::size_t i = 0; i < cavities_.size(); ++i) {
    Cavity& cavity = cavities_[i];
    if (cavity.law == nullptr) continue;
    const auto nc = static_cast<Index>(cavity.nodes.size());
    // q⁺(p) = q* + p dt² M⁻¹ g on the cavity's nodes (the others do not change V).
    double wall_slope = 0;  // dV/dp of the wall at p = 0, gᵀ dt² M⁻¹ g
    for (Index k = 0; k < nc; ++k)
      wall_slope += dt * dt / mass_[cavity.nodes[static_cast<std::size_t>(k)]] *
                    cavity.step_gradient.col(k).squaredNorm();
    bool law_failed = false;
    double blood_volume = 0;
    auto h = [&](double p, double& out) {
      for (Index k = 0; k < nc; ++k) {
        const int node = cavity.nodes[static_cast<std::size_t>(k)];
        cavity.positions.col(k) = state_.x.segment<3>(3 * node) +
                                  (p * dt * dt / mass_[node]) * cavity.step_gradient.col(k);
      }
      if (!cavity.law->EndVolume(t, dt, p, blood_volume) || !std::isfinite(blood_volume)) {
        law_failed = true;
        return false;
      }
      out = cavity.volume.Compute(cavity.positions) - blood_volume;
      return true;
    };
    const double v_now = CavityVolume(i);
    MassSpringCavityState& cs = state_.cavities[i];
    double p = cs.pressure, slope = 0;
    const double estimate = wall_slope + cs.compliance;  // dh/dp
    auto first_step = [estimate](double h0) {  // a Newton step on the estimate, else ±1 Pa
      const double step = -h0 / estimate;
      return std::abs(step) > 0 && std::isfinite(step) ? step : (h0 > 0 ? -1.0 : 1.0);
    };
    if (!SolveIncreasingRoot(h, cs.pressure, first_step, 1e-13 * v_now, p, &slope)) {
      const std::string& cname = params_.cavities[i].name;
      failure_detail_ =
          law_failed ? fmt::format(
                           "the blood coupled to cavity '{}' could not answer at t = {} s (it "
                           "must step with this object's dt, {} s, right after it)",
                           cname, t, dt)
                     : fmt::format(
                           "no pressure makes cavity '{}' enclose the blood's volume at t = {} "
                           "s (dt {} s)",
                           cname, t, dt);
      return false;
    }
    if (slope > wall_slope) cs.compliance = slope - wall_slope;
    cs.pressure = p;
    for (Index k = 0; k < nc; ++k) {
      const int node = cavity.nodes[static_cast<std::size_t>(k)];
      const Vec3 dv = (p * dt / mass_[node]) * cavity.step_gradient.col(k);
      state_.x.segment<3>(3 * n + 3 * node) += dv;
      state_.x.segment<3>(3 * node) += dt * dv;
    }
  }
  return true;
}

}  // namespace gipsi
