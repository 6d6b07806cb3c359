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

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/models/fem/fem_solid.h"

namespace gipsi {

void FemSolid::MakeCavities(const Mesh& domain, const BoundarySurface& bnd) {
  const Index n = domain.num_nodes();
  // A split solid's cavities are the whole mesh's: selected on it when it is there, else on
  // the parts and gathered (the selection's surface then numbers its vertices by whole-mesh
  // node, so the cavity is the same either way).
  auto declare = [this](FieldInfo info) { return DeclareField(std::move(info)); };
  constexpr std::string_view kPressureDescription =
      "pressure in the cavity, acting on its faces (follower load)";
  if (dist_ && !dist_->has_whole_mesh()) {
    for (const CavitySpec& spec : params_.cavities) {
      WholeFaceSelection selected = dist_->SelectWholeFaces(spec.region);  // collective
      std::vector<int> all(selected.faces.size());
      std::iota(all.begin(), all.end(), 0);
      WallCavity wall = MakeWallCavity(this->name(), spec, selected.surface, std::move(all),
                                       declare, kPressureDescription);
      wall.faces = std::move(selected.faces);
      cavities_.emplace_back(std::move(wall)).gradient = VecX::Zero(3 * n);
    }
  } else if (!params_.cavities.empty()) {
    for (WallCavity& wall :
         MakeWallCavities(this->name(), params_.cavities, dist_ ? dist_->whole_mesh() : domain,
                          dist_ ? dist_->whole_boundary() : bnd, declare, kPressureDescription))
      cavities_.emplace_back(std::move(wall)).gradient = VecX::Zero(3 * n);
  }
  if (dist_ && !cavities_.empty()) {
    // The whole cavity's surface on every process; its faces on this one, in part numbering.
    const std::span<const int> whole_node = dist_->whole_node();
    std::vector<std::pair<int, int>> local_of;  // (whole-mesh node, local node), sorted
    local_of.reserve(whole_node.size());
    for (std::size_t i = 0; i < whole_node.size(); ++i)
      local_of.emplace_back(whole_node[i], static_cast<int>(i));
    std::sort(local_of.begin(), local_of.end());
    const std::span<const int> whole_face = dist_->whole_face();
    std::vector<int> my_whole_faces(whole_face.begin(), whole_face.end());
    std::sort(my_whole_faces.begin(), my_whole_faces.end());
    for (Cavity& cavity : cavities_) {
      // Surface triangle k is whole face cavity.faces[k] (MakeCavitySurface keeps the order).
      std::vector<int> whole_faces = cavity.faces, faces;
      for (std::size_t k = 0; k < whole_faces.size(); ++k)
        if (std::binary_search(my_whole_faces.begin(), my_whole_faces.end(), whole_faces[k]))
          cavity.my_triangles.push_back(static_cast<int>(k));
      std::sort(whole_faces.begin(), whole_faces.end());
      for (std::size_t f = 0; f < whole_face.size(); ++f)
        if (std::binary_search(whole_faces.begin(), whole_faces.end(), whole_face[f]))
          faces.push_back(static_cast<int>(f));
      cavity.faces = std::move(faces);
      for (const int node : cavity.nodes) {
        const auto it =
            std::lower_bound(local_of.begin(), local_of.end(), std::make_pair(node, -1));
        cavity.local_node.push_back(it != local_of.end() && it->first == node ? it->second : -1);
      }
      // A rim half-edge a → b runs along one surface triangle in that direction.
      const Triangles& triangles = cavity.volume.triangles();
      std::vector<std::pair<int, int>> my_edges;
      for (int k : cavity.my_triangles)
        for (int i = 0; i < 3; ++i)
          my_edges.emplace_back(triangles(i, k), triangles((i + 1) % 3, k));
      std::sort(my_edges.begin(), my_edges.end());
      for (const auto& loop : cavity.volume.loops()) {
        auto& mine = cavity.my_loops.emplace_back();
        for (const auto& edge : loop)
          if (std::binary_search(my_edges.begin(), my_edges.end(), edge)) mine.push_back(edge);
      }
    }
  }
}

double FemSolid::CavityVolume(std::size_t i) const {
  GIPSI_CHECK(i < cavities_.size());
  if (!dist_) return cavities_[i].Volume(positions_);
  return SplitCavityVolume(cavities_[i], u().data(), nullptr);
}

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
    double v = 0;
    if (dist_) {
      v = SplitCavityVolume(cavity, u, &cavity.gradient);
    } else {
      CavityPositions(cavity, u);
      v = cavity.volume.Compute(cavity.positions, &cavity.local_gradient);
      cavity.gradient.setZero();
      for (std::size_t k = 0; k < cavity.nodes.size(); ++k)
        cavity.gradient.segment<3>(3 * static_cast<Index>(cavity.nodes[k])) +=
            cavity.local_gradient.col(static_cast<Index>(k));
    }
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
    const double p = state_.cavities[c].pressure;
    if (dist_) {  // the whole gradient on owned nodes, the forces being summed over the processes
      SplitCavityVolume(cavity, u().data(), &cavity_gradient_);
      const Index owned = dist_->owned();
      f.head(owned) += p * cavity_gradient_.head(owned);
      continue;
    }
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k)
      cavity.positions.col(static_cast<Index>(k)) = positions_.col(cavity.nodes[k]);
    cavity.volume.Compute(cavity.positions, &cavity.local_gradient);
    for (std::size_t k = 0; k < cavity.nodes.size(); ++k)
      f.segment<3>(3 * static_cast<Index>(cavity.nodes[k])) +=
          p * cavity.local_gradient.col(static_cast<Index>(k));
  }
}

void FemSolid::CavityPositions(const Cavity& cavity, const double* u) const {
  GIPSI_CHECK(!dist_);
  for (std::size_t k = 0; k < cavity.nodes.size(); ++k) {
    const auto node = static_cast<Index>(cavity.nodes[k]);
    cavity.positions.col(static_cast<Index>(k)) =
        rest_.segment<3>(3 * node) + Eigen::Map<const Vec3>(u + 3 * node);
  }
}

double FemSolid::SplitCavityVolume(const Cavity& cavity, const double* u, VecX* gradient) const {
  // As EnclosedVolume::Compute, over this rank's triangles and rim half-edges.
  auto x = [&](int vertex) -> Vec3 {
    const int node = cavity.local_node[static_cast<std::size_t>(vertex)];
    GIPSI_CHECK(node >= 0, "a cavity vertex of this rank's faces is not on this rank");
    return rest_.segment<3>(3 * node) + Eigen::Map<const Vec3>(u + 3 * node);
  };
  auto add = [&](int vertex, const Vec3& g) {
    const int node = cavity.local_node[static_cast<std::size_t>(vertex)];
    gradient->segment<3>(3 * static_cast<Index>(node)) += g;
  };
  if (gradient) gradient->setZero(3 * num_nodes());
  const Triangles& triangles = cavity.volume.triangles();
  double volume = 0;
  for (int k : cavity.my_triangles) {
    const int i0 = triangles(0, k), i1 = triangles(1, k), i2 = triangles(2, k);
    const Vec3 x0 = x(i0), x1 = x(i1), x2 = x(i2);
    volume += x0.dot(x1.cross(x2)) / 6.0;
    if (gradient) {
      add(i0, x1.cross(x2) / 6.0);
      add(i1, x2.cross(x0) / 6.0);
      add(i2, x0.cross(x1) / 6.0);
    }
  }
  // The rim centroids: each loop vertex starts one half-edge, on one rank.
  const std::size_t loops = cavity.my_loops.size();
  std::vector<double> sums(3 * loops + 1, 0.0);
  for (std::size_t l = 0; l < loops; ++l)
    for (const auto& edge : cavity.my_loops[l]) Eigen::Map<Vec3>(&sums[3 * l]) += x(edge.first);
  dist_->Reduce({sums.data(), 3 * loops}, false);
  std::vector<Vec3> centroid(loops);
  for (std::size_t l = 0; l < loops; ++l)
    centroid[l] =
        Eigen::Map<const Vec3>(&sums[3 * l]) / static_cast<double>(cavity.volume.loops()[l].size());
  // The caps: this rank's fan triangles (b, a, c), and its share of ∂V/∂c.
  std::fill(sums.begin(), sums.end(), 0.0);
  for (std::size_t l = 0; l < loops; ++l) {
    const Vec3& c = centroid[l];
    Eigen::Map<Vec3> dc(&sums[3 * l]);
    for (const auto& [a, b] : cavity.my_loops[l]) {
      const Vec3 xb = x(b), xa = x(a);
      volume += xb.dot(xa.cross(c)) / 6.0;
      if (gradient) {
        add(b, xa.cross(c) / 6.0);
        add(a, c.cross(xb) / 6.0);
        dc += xb.cross(xa) / 6.0;
      }
    }
  }
  sums[3 * loops] = volume;
  dist_->Reduce(sums, false);
  volume = sums[3 * loops];
  if (!gradient) return volume;
  for (std::size_t l = 0; l < loops; ++l) {
    const Vec3 share =
        Eigen::Map<const Vec3>(&sums[3 * l]) / static_cast<double>(cavity.volume.loops()[l].size());
    for (const auto& edge : cavity.my_loops[l]) add(edge.first, share);
  }
  dist_->SumShared(*gradient);
  return volume;
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
