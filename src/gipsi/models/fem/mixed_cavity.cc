// MixedSolid's cavities, coupled to blood through a CavityLaw (cavity_law.h) or loaded by their
// written pressure.
//
// A coupled cavity's pressure p is a bordered unknown of Newton's iterate, as for FemSolid
// (fem_cavity.cc has the formulation and why): the step solves
//   r_u = (the mixed element's residual) − p ∂V/∂u = 0,   r_p = V(u) − V_b(p) = 0,
// with V the volume the curved faces enclose (quadratic_volume.h) and V_b the blood's end
// volume. Newton eliminates p through the rank-one term (1/C) ∂V/∂u ⊗ ∂V/∂u, C = −dV_b/dp,
// solved with the factorised saddle-point matrix by Woodbury; the sparse part gets the
// follower tangent −p ∂²V/∂u² of the faces, which is symmetric (the load is the gradient of
// p V), so the "ldlt" solver keeps it whole.

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/models/fem/mixed_solid.h"

namespace gipsi {
namespace {

/// The reversed 6-node triangle: a boundary face points out of the tissue, into the cavity;
/// the cavity's faces point out of it.
constexpr int kReversed[6] = {0, 2, 1, 5, 4, 3};

}  // namespace

void MixedSolid::MakeCavities(const Mesh& domain) {
  std::vector<WallCavity> walls = MakeWallCavities(
      path(), params_.cavities, domain, boundary(),
      [this](FieldInfo info) { return DeclareField(std::move(info)); },
      "pressure in the cavity, acting on its curved faces (follower load)");
  const Index nn = mesh_.num_nodes();
  for (WallCavity& wall : walls) {
    QuadraticTriangles faces(6, static_cast<Index>(wall.faces.size()));
    for (std::size_t k = 0; k < wall.faces.size(); ++k)
      for (int a = 0; a < 6; ++a)
        faces(a, static_cast<Index>(k)) = faces_(kReversed[a], wall.faces[k]);
    std::vector<std::vector<QuadraticEnclosedVolume::RimEdge>> loops;
    for (const auto& loop : wall.volume.loops()) {
      auto& rim = loops.emplace_back();
      for (const auto& [a, b] : loop) {
        const int va = wall.nodes[static_cast<std::size_t>(a)];
        const int vb = wall.nodes[static_cast<std::size_t>(b)];
        rim.push_back({va, vb, mesh_.EdgeNode(va, vb)});
      }
    }
    Vec3 origin = Vec3::Zero();
    for (int node : wall.nodes) origin += mesh_.rest.col(node);
    origin /= static_cast<double>(wall.nodes.size());
    std::vector<int> boundary_faces = wall.faces;
    cavities_.push_back(
        Cavity{.wall = std::move(wall),
               .volume = QuadraticEnclosedVolume(std::move(faces), std::move(loops), nn, origin),
               .boundary_faces = std::move(boundary_faces),
               .gradient = VecX::Zero(jac_.rows()),
               .node_gradient = Points::Zero(3, nn)});
  }
  state_.cavity_pressure = VecX::Zero(static_cast<Index>(cavities_.size()));
  cavity_pressure_begin_ = state_.cavity_pressure;
  node_positions_ = Points::Zero(3, nn);
}

void MixedSolid::AttachCavityLaw(std::string_view cavity, CavityLaw* law) {
  GIPSI_CHECK(law != nullptr);
  const std::size_t i = FindCavity(path(), type_name(), params_.cavities, cavity);
  if (cavities_[i].wall.law != nullptr) ThrowCavityAlreadyCoupled(path(), cavity);
  cavities_[i].wall.law = law;
  bordered_ = 0;
  for (const Cavity& c : cavities_) bordered_ += c.wall.law != nullptr ? 1 : 0;
  const Index n = jac_.rows();
  newton_x_.setZero(n + bordered_);
  iterate_z_.setZero(n);
  iterate_r_.setZero(n);
  newton_->Prepare(jac_, bordered_);
}

double MixedSolid::CavityVolume(std::size_t i) const {
  GIPSI_CHECK(i < cavities_.size());
  const Index nn = mesh_.num_nodes();
  node_positions_ = mesh_.rest + Eigen::Map<const Points>(state_.z.data(), 3, nn);
  return cavities_[i].volume.Compute(node_positions_);
}

double MixedSolid::CavityPressure(std::size_t i) const {
  GIPSI_CHECK(i < cavities_.size());
  return state_.cavity_pressure[static_cast<Index>(i)];
}

bool MixedSolid::AddCavityLoads(const VecX& z, VecX& r, double* jv, bool laws) const {
  if (bordered_ == 0) return true;
  const Index nn = mesh_.num_nodes();
  node_positions_ = mesh_.rest + Eigen::Map<const Points>(z.data(), 3, nn);
  for (std::size_t c = 0; c < cavities_.size(); ++c) {
    const Cavity& cavity = cavities_[c];
    if (cavity.wall.law == nullptr) continue;
    const double p = state_.cavity_pressure[static_cast<Index>(c)];
    const double v = cavity.volume.Compute(node_positions_, &cavity.node_gradient);
    cavity.gradient.head(3 * nn) = Eigen::Map<const VecX>(cavity.node_gradient.data(), 3 * nn);
    // The load on every node (the held ones' share goes to their reactions); the low-rank
    // term's vector is zero on the held dofs.
    r.head(3 * nn) -= p * cavity.gradient.head(3 * nn);
    for (int dof : constrained_dofs_) cavity.gradient[dof] = 0;
    if (laws) {
      double vb = 0;
      if (!cavity.wall.law->EndVolume(step_time_, step_dt_, p, vb) || !std::isfinite(vb)) {
        failed_cavity_ = static_cast<int>(c);
        return false;
      }
      cavity.volume_residual = v - vb;
      // At the current pressure with every residual: the Woodbury solve and the elimination of
      // Δp then use it even while a factorisation of an older tangent is kept.
      cavity.stiffness = CavityLawStiffness(*cavity.wall.law, step_time_, step_dt_, p, vb);
      if (!(cavity.stiffness > 0)) {  // p would not be determined by the volume
        failed_cavity_ = static_cast<int>(c);
        return false;
      }
    }
    if (jv == nullptr || p == 0) continue;
    const BoundarySurface& bnd = boundary();
    for (Index k = 0; k < cavity.volume.faces().cols(); ++k) {
      const FaceHessian h = cavity.volume.Hessian(k, node_positions_);
      const auto f = static_cast<std::size_t>(cavity.boundary_faces[static_cast<std::size_t>(k)]);
      const Index tet = bnd.face_to_tet[f];
      int local[6];
      for (int a = 0; a < 6; ++a) local[a] = face_local_(kReversed[a], static_cast<Index>(f));
      const int* idx =
          element_value_index_.data() + static_cast<std::size_t>(tet) * kLocal * kLocal;
      for (int b = 0; b < 6; ++b)
        for (int j = 0; j < 3; ++j)
          for (int a = 0; a < 6; ++a)
            for (int i = 0; i < 3; ++i)
              jv[idx[(3 * local[b] + j) * kLocal + 3 * local[a] + i]] -=
                  p * h(3 * a + i, 3 * b + j);
    }
  }
  return true;
}

void MixedSolid::LowRankTerm(int k, const VecX*& b, double& w) const {
  for (const Cavity& cavity : cavities_) {
    if (cavity.wall.law == nullptr) continue;
    if (k-- == 0) {
      b = &cavity.gradient;
      w = cavity.stiffness;
      return;
    }
  }
  GIPSI_CHECK(false);
}

void MixedSolid::GiveIterate(VecX& x) const {
  const Index n = state_.z.size();
  x.head(n) = state_.z;
  Index k = n;
  for (std::size_t c = 0; c < cavities_.size(); ++c)
    if (cavities_[c].wall.law != nullptr) x[k++] = state_.cavity_pressure[static_cast<Index>(c)];
}

void MixedSolid::TakeIterate(const VecX& x) {
  const Index n = state_.z.size();
  state_.z = x.head(n);
  Index k = n;
  for (std::size_t c = 0; c < cavities_.size(); ++c)
    if (cavities_[c].wall.law != nullptr) state_.cavity_pressure[static_cast<Index>(c)] = x[k++];
}

}  // namespace gipsi
