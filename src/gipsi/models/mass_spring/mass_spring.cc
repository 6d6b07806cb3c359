#include "gipsi/models/mass_spring/mass_spring.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/quality.h"

namespace gipsi {
namespace {

Eigen::Matrix2Xi UniqueEdges(const Mesh& mesh) {
  std::set<std::pair<int, int>> edges;
  auto add = [&](int a, int b) { edges.emplace(std::min(a, b), std::max(a, b)); };
  for (Index e = 0; e < mesh.num_tets(); ++e)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) add(mesh.tets(i, e), mesh.tets(j, e));
  if (mesh.num_tets() == 0)
    for (Index e = 0; e < mesh.num_triangles(); ++e)
      for (int i = 0; i < 3; ++i) add(mesh.triangles(i, e), mesh.triangles((i + 1) % 3, e));
  Eigen::Matrix2Xi out(2, static_cast<Index>(edges.size()));
  Index s = 0;
  for (const auto& [a, b] : edges) {
    out(0, s) = a;
    out(1, s) = b;
    ++s;
  }
  return out;
}

}  // namespace

MassSpring::MassSpring(std::string name, std::shared_ptr<const Mesh> domain,
                       const MassSpringParams& params, std::unique_ptr<OdeIntegrator> integrator)
    : SimObject(std::move(name)), params_(params), integrator_(std::move(integrator)) {
  GIPSI_CHECK(domain != nullptr && integrator_ != nullptr);
  const Mesh& mesh = *domain;
  if (mesh.num_tets() == 0 && mesh.num_triangles() == 0)
    throw InputError(
        fmt::format("object '{}': a MassSpring domain needs tets or triangles", this->path()));
  SetGeometry(domain, MakeBoundary(mesh));
  const Index n = mesh.num_nodes();

  springs_ = UniqueEdges(mesh);
  mass_ = VecX::Zero(n);
  if (mesh.num_tets() > 0) {
    for (Index e = 0; e < mesh.num_tets(); ++e) {
      double volume = std::abs(
          TetSignedVolume(mesh.nodes.col(mesh.tets(0, e)), mesh.nodes.col(mesh.tets(1, e)),
                          mesh.nodes.col(mesh.tets(2, e)), mesh.nodes.col(mesh.tets(3, e))));
      for (int a = 0; a < 4; ++a) mass_[mesh.tets(a, e)] += params_.density * volume / 4.0;
    }
  } else {
    for (Index e = 0; e < mesh.num_triangles(); ++e) {
      const Vec3 p0 = mesh.nodes.col(mesh.triangles(0, e));
      double area = 0.5 * (mesh.nodes.col(mesh.triangles(1, e)) - p0)
                              .cross(mesh.nodes.col(mesh.triangles(2, e)) - p0)
                              .norm();
      for (int a = 0; a < 3; ++a)
        mass_[mesh.triangles(a, e)] += params_.density * params_.thickness * area / 3.0;
    }
  }
  Finish();
}

MassSpring::MassSpring(std::string name, const Points& nodes, const Eigen::Matrix2Xi& springs,
                       const VecX& masses, const MassSpringParams& params,
                       std::unique_ptr<OdeIntegrator> integrator)
    : SimObject(std::move(name)), params_(params), integrator_(std::move(integrator)) {
  GIPSI_CHECK(integrator_ != nullptr);
  const Index n = nodes.cols();
  if (masses.size() != n)
    throw InputError(
        fmt::format("object '{}': {} masses for {} nodes", this->path(), masses.size(), n));
  for (Index s = 0; s < springs.cols(); ++s)
    for (int a = 0; a < 2; ++a)
      if (springs(a, s) < 0 || springs(a, s) >= n)
        throw InputError(fmt::format("object '{}': spring {} refers to node {} (have {})",
                                     this->path(), s, springs(a, s), n));
  auto mesh = std::make_shared<Mesh>();
  mesh->nodes = nodes;
  BoundarySurface boundary;
  for (Index i = 0; i < n; ++i) boundary.vertex_to_node.push_back(static_cast<int>(i));
  SetGeometry(std::move(mesh), std::move(boundary));
  springs_ = springs;
  mass_ = masses;
  Finish();
}

void MassSpring::Finish() {
  if (!params_.law) params_.law = std::make_shared<HookeSpring>();
  hooke_ = dynamic_cast<const HookeSpring*>(params_.law.get()) != nullptr;
  BindState(state_);  // checkpoints and snapshots; StateRestored rebuilds what derives from it
  const Mesh& mesh = domain();
  const Index n = mesh.num_nodes();
  rest_length_.resize(num_springs());
  for (Index s = 0; s < num_springs(); ++s) {
    rest_length_[s] = (mesh.nodes.col(springs_(1, s)) - mesh.nodes.col(springs_(0, s))).norm();
    if (!(rest_length_[s] > 0))
      throw InputError(
          fmt::format("object '{}': spring between nodes {} and {} has zero rest "
                      "length (coincident nodes)",
                      this->path(), springs_(0, s), springs_(1, s)));
  }
  for (Index i = 0; i < n; ++i)
    if (!(mass_[i] > 0))
      throw InputError(
          fmt::format("object '{}': node {} has no mass (it belongs to no element "
                      "or only to degenerate ones)",
                      this->path(), i));

  state_.x = VecX::Zero(6 * n);
  state_.x.head(3 * n) = Eigen::Map<const VecX>(mesh.nodes.data(), 3 * n);
  positions_ = mesh.nodes;
  state_.external_force = Points::Zero(3, n);
  force_.resize(3 * n);
  integrator_->Prepare(ode_size());
  symplectic_ = dynamic_cast<const SymplecticEuler*>(integrator_.get()) != nullptr;
  state_.nodal_active_tension = VecX::Zero(n);
  state_.fibres.Write() = Points(3, mesh.num_tets());
  const Vec3 fibre = params_.fibre.normalized();
  if (!fibre.allFinite())
    throw InputError(fmt::format("object '{}': the fibre direction must be non-zero", path()));
  state_.fibres.Write().colwise() = fibre;
  tet_rest_volume_.resize(mesh.num_tets());
  for (Index e = 0; e < mesh.num_tets(); ++e)
    tet_rest_volume_[e] =
        TetSignedVolume(mesh.nodes.col(mesh.tets(0, e)), mesh.nodes.col(mesh.tets(1, e)),
                        mesh.nodes.col(mesh.tets(2, e)), mesh.nodes.col(mesh.tets(3, e)));
  if (params_.volume_stiffness > 0 && mesh.num_tets() == 0)
    throw InputError(fmt::format("object '{}': volume_stiffness needs a tet domain", this->path()));
  UpdateActiveWeights();

  using L = FieldLocation;
  using A = FieldAccess;
  mech_ = DeclareMechanicalFields();
  f_mass_ = DeclareField({"mass", L::kNode, 1, "kg", A::kRead, "lumped node mass"});
  f_kinetic_ = DeclareField({"kinetic_energy", L::kGlobal, 1, "J", A::kRead, "½ Σ m v²"});
  f_potential_ = DeclareField(
      {"potential_energy", L::kGlobal, 1, "J", A::kRead, "spring plus gravitational energy"});
  f_momentum_ = DeclareField({"momentum", L::kGlobal, 3, "kg·m/s", A::kRead, "Σ m v"});
  if (mesh.num_tets() > 0)
    f_fibre_ = DeclareField({"fibre", L::kElement, 3, "1", A::kReadWrite,
                             "fibre direction per tet in the reference configuration (unit)"});
  f_nodal_active_ = DeclareField(
      {"nodal_active_tension", L::kNode, 1, "Pa", A::kReadWrite,
       "active tension per node; springs contract with the mean of their nodes' (fibre-weighted)"});
  if (!params_.cavities.empty() && mesh.num_tets() == 0)
    throw InputError(fmt::format("object '{}': cavities need a tet domain", path()));
  SetUpCavities();
}

void MassSpring::CalcForces(double /*t*/, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> f,
                            CoupledPressures coupled) const {
  const Index n = num_nodes();
  const auto q = x.head(3 * n);
  const auto v = x.tail(3 * n);
  const SpringLaw& law = *params_.law;
  for (Index i = 0; i < n; ++i) {
    f.segment<3>(3 * i) = mass_[i] * (params_.gravity - params_.drag * v.segment<3>(3 * i)) +
                          state_.external_force.col(i);
  }
  for (Index s = 0; s < num_springs(); ++s) {
    const Index a = springs_(0, s), b = springs_(1, s);
    const Vec3 d = q.segment<3>(3 * b) - q.segment<3>(3 * a);
    const double length = d.norm();
    if (length <= 0) continue;  // coincident nodes: no direction; CheckState reports stretch
    const Vec3 dir = d / length;
    const double rate = (v.segment<3>(3 * b) - v.segment<3>(3 * a)).dot(dir);
    // Hooke is the common case: inline it rather than pay a virtual call per spring.
    const double tension = hooke_ ? params_.stiffness * (length - rest_length_[s])
                                  : law.Tension(length, rest_length_[s], params_.stiffness);
    const double active =
        any_active_ ? 0.5 * (state_.nodal_active_tension[a] + state_.nodal_active_tension[b]) *
                          active_weight_[s]
                    : 0.0;
    const Vec3 fs = (tension + active + params_.damping * rate) * dir;
    f.segment<3>(3 * a) += fs;
    f.segment<3>(3 * b) -= fs;
  }
  const BoundarySurface& bnd = boundary();
  const BoundaryConditions& bcs = boundary_conditions();
  for (Index j = 0; j < bnd.num_vertices(); ++j)
    f.segment<3>(3 * bnd.vertex_to_node[static_cast<std::size_t>(j)]) += bcs.force(j);
  if (bcs.any_face_load()) {
    for (Index t = 0; t < bnd.num_triangles(); ++t) {
      const int i0 = bnd.vertex_to_node[static_cast<std::size_t>(bnd.triangles(0, t))];
      const int i1 = bnd.vertex_to_node[static_cast<std::size_t>(bnd.triangles(1, t))];
      const int i2 = bnd.vertex_to_node[static_cast<std::size_t>(bnd.triangles(2, t))];
      const Vec3 p0 = q.segment<3>(3 * i0);
      // area_normal = 2·area·n (outward for tet boundaries).
      const Vec3 area_normal = (q.segment<3>(3 * i1) - p0).cross(q.segment<3>(3 * i2) - p0);
      const Vec3 load = (0.5 / 3.0) * (-bcs.pressure(t) * area_normal +
                                       area_normal.norm() * Vec3(bcs.traction(t)));
      f.segment<3>(3 * i0) += load;
      f.segment<3>(3 * i1) += load;
      f.segment<3>(3 * i2) += load;
    }
  }
  AddVolumeForces(q, f);
  AddCavityForces(q, f, coupled == CoupledPressures::kIncluded);
}

void MassSpring::CalcDerivative(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const {
  CalcDerivative(t, x, xdot, CoupledPressures::kIncluded);
}

void MassSpring::CalcDerivative(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot,
                                CoupledPressures coupled) const {
  const Index n = num_nodes();
  CalcForces(t, x, force_, coupled);
  xdot.head(3 * n) = x.tail(3 * n);
  for (Index i = 0; i < n; ++i)
    xdot.segment<3>(3 * n + 3 * i) = force_.segment<3>(3 * i) / mass_[i];
  // Constrained axes: no acceleration; displacement-held axes do not move within a step.
  const BoundarySurface& bnd = boundary();
  const BoundaryConditions& bcs = boundary_conditions();
  for (Index j = 0; j < bnd.num_vertices(); ++j) {
    const Index node = bnd.vertex_to_node[static_cast<std::size_t>(j)];
    for (int a = 0; a < 3; ++a) {
      ConstraintKind kind = bcs.kind(j, a);
      if (kind == ConstraintKind::kFree) continue;
      xdot[3 * n + 3 * node + a] = 0;
      if (kind == ConstraintKind::kDisplacement) xdot[3 * node + a] = 0;
    }
  }
}

void MassSpring::ApplyConstraints(double /*dt*/) {
  const Index n = num_nodes();
  const BoundarySurface& bnd = boundary();
  const BoundaryConditions& bcs = boundary_conditions();
  const Points& rest = domain().nodes;
  for (Index j = 0; j < bnd.num_vertices(); ++j) {
    const Index node = bnd.vertex_to_node[static_cast<std::size_t>(j)];
    for (int a = 0; a < 3; ++a) {
      switch (bcs.kind(j, a)) {
        case ConstraintKind::kFree:
          break;
        case ConstraintKind::kDisplacement:
          state_.x[3 * node + a] = rest(a, node) + bcs.value(j)[a];
          state_.x[3 * n + 3 * node + a] = 0;
          break;
        case ConstraintKind::kVelocity:
          state_.x[3 * n + 3 * node + a] = bcs.value(j)[a];
          break;
      }
    }
  }
}

StepStatus MassSpring::CheckState() const {
  for (Index i = 0; i < state_.x.size(); ++i)
    if (!std::isfinite(state_.x[i]))
      return StepStatus::Diverged("non-finite position or velocity at node",
                                  (i % (3 * num_nodes())) / 3, state_.x[i]);
  const Index n = num_nodes();
  for (Index s = 0; s < num_springs(); ++s) {
    const double length =
        (state_.x.segment<3>(3 * springs_(1, s)) - state_.x.segment<3>(3 * springs_(0, s))).norm();
    if (length > params_.max_stretch * rest_length_[s])
      return StepStatus::Diverged(
          "spring stretched beyond max_stretch times its rest length (time step too large for "
          "an explicit integrator?); spring",
          s, length / rest_length_[s]);
  }
  (void)n;
  return StepStatus::Ok();
}

struct MassSpring::StepOde {
  const MassSpring& object;
  CoupledPressures coupled;
  [[nodiscard]] Index ode_size() const { return object.ode_size(); }
  [[nodiscard]] Index ode_num_positions() const { return object.ode_num_positions(); }
  void CalcDerivative(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const {
    object.CalcDerivative(t, x, xdot, coupled);
  }
};

StepStatus MassSpring::DoStep(double t, double dt) {
  failure_detail_.clear();
  ApplyConstraints(dt);
  const bool coupled = std::any_of(cavities_.begin(), cavities_.end(),
                                   [](const Cavity& c) { return c.law != nullptr; });
  // With coupled cavities, the step with p = 0 for them, then their pressures (mass_spring.h).
  if (coupled) BeginCoupledStep();
  const StepOde ode{*this, coupled ? CoupledPressures::kLeftOut : CoupledPressures::kIncluded};
  if (!integrator_->Step(OdeView(ode), t, dt, state_.x)) {
    failure_detail_ = fmt::format("{}: {}", integrator_->name(), integrator_->failure());
    return StepStatus::Failed("the implicit integrator's solve failed (state left at the start)");
  }
  if (coupled && !SolveCoupledCavities(t, dt))
    return StepStatus::Failed("the cavity pressure could not be solved with the blood");
  const Index n = num_nodes();
  positions_ = Eigen::Map<const Points>(state_.x.data(), 3, n);
  const StepStatus status = CheckState();
  if (!status.ok()) return status;
  if (const Index e = FirstInvertedTet(); e >= 0) {
    failure_detail_ = domain().TetName(e) + " inverted";  // as the mesh file names it
    return StepStatus::Diverged(
        "a tet was inverted (volume <= 0; time step too large, or a load the volume term cannot "
        "hold); tet",
        domain().TetId(e));
  }
  return status;
}

double MassSpring::stable_dt_estimate() const {
  VecX k_sum = VecX::Zero(num_nodes());
  for (Index s = 0; s < num_springs(); ++s) {
    k_sum[springs_(0, s)] += params_.stiffness;
    k_sum[springs_(1, s)] += params_.stiffness;
  }
  // The volume term's stiffness at node a of tet e: K |∂V/∂x_a|² / V0.
  const Mesh& mesh = domain();
  for (Index e = 0; e < mesh.num_tets() && params_.volume_stiffness > 0; ++e)
    for (int a = 0; a < 4; ++a) {
      const Vec3 p = mesh.nodes.col(mesh.tets((a + 1) % 4, e)),
                 q = mesh.nodes.col(mesh.tets((a + 2) % 4, e)),
                 r = mesh.nodes.col(mesh.tets((a + 3) % 4, e));
      const double grad = (q - p).cross(r - p).norm() / 6.0;
      k_sum[mesh.tets(a, e)] +=
          params_.volume_stiffness * grad * grad / std::abs(tet_rest_volume_[e]);
    }
  double omega2 = 0;
  for (Index i = 0; i < num_nodes(); ++i) omega2 = std::max(omega2, 4.0 * k_sum[i] / mass_[i]);
  return omega2 > 0 ? 2.0 / std::sqrt(omega2) : std::numeric_limits<double>::infinity();
}

double MassSpring::KineticEnergy() const {
  const Index n = num_nodes();
  double e = 0;
  for (Index i = 0; i < n; ++i)
    e += 0.5 * mass_[i] * state_.x.segment<3>(3 * n + 3 * i).squaredNorm();
  return e;
}

double MassSpring::PotentialEnergy() const {
  double e = 0;
  for (Index s = 0; s < num_springs(); ++s) {
    const double length =
        (state_.x.segment<3>(3 * springs_(1, s)) - state_.x.segment<3>(3 * springs_(0, s))).norm();
    e += params_.law->Energy(length, rest_length_[s], params_.stiffness);
  }
  for (Index i = 0; i < num_nodes(); ++i)
    e -= mass_[i] * params_.gravity.dot(state_.x.segment<3>(3 * i) - domain().nodes.col(i));
  return e + VolumeEnergy();
}

Vec3 MassSpring::Momentum() const {
  const Index n = num_nodes();
  Vec3 p = Vec3::Zero();
  for (Index i = 0; i < n; ++i) p += mass_[i] * state_.x.segment<3>(3 * n + 3 * i);
  return p;
}

const double* MassSpring::DoFieldMemory(FieldId id) const {
  if (id == mech_.position) return positions_.data();
  if (id == mech_.velocity) return state_.x.data() + 3 * num_nodes();
  if (id == mech_.external_force) return state_.external_force.data();
  return nullptr;
}

void MassSpring::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  const Index n = num_nodes();
  const auto& v2n = boundary().vertex_to_node;
  auto node_block = [&](Index offset) {  // 3 by N view into state_.x
    return Eigen::Map<const Points>(state_.x.data() + offset, 3, n);
  };
  if (ReadBoundaryKinematics(mech_, id, positions_, state_.x.data() + 3 * n, out)) return;
  if (id == mech_.position) {
    out = positions_;
  } else if (id == mech_.velocity) {
    out = node_block(3 * n);
  } else if (id == mech_.displacement) {
    out = positions_ - domain().nodes;
  } else if (id == mech_.external_force) {
    out = state_.external_force;
  } else if (id == f_mass_) {
    out = mass_.transpose();
  } else if (id == mech_.reaction_force) {
    // Reaction = m·a_prescribed − f = −f on constrained axes (prescribed acceleration is zero).
    CalcForces(time(), state_.x, force_);
    const BoundaryConditions& bcs = boundary_conditions();
    for (std::size_t j = 0; j < v2n.size(); ++j) {
      const auto col = static_cast<Index>(j);
      for (int a = 0; a < 3; ++a)
        out(a, col) = bcs.kind(col, a) == ConstraintKind::kFree ? 0.0 : -force_[3 * v2n[j] + a];
    }
  } else if (id == f_kinetic_) {
    out(0, 0) = KineticEnergy();
  } else if (id == f_potential_) {
    out(0, 0) = PotentialEnergy();
  } else if (id == f_momentum_) {
    out.col(0) = Momentum();
  } else if (id == f_fibre_) {
    out = state_.fibres.get();
  } else if (id == f_nodal_active_) {
    out = state_.nodal_active_tension.transpose();
  } else {
    for (std::size_t i = 0; i < cavities_.size(); ++i) {
      if (id == cavities_[i].f_volume) out(0, 0) = CavityVolume(i);
      if (id == cavities_[i].f_pressure) out(0, 0) = state_.cavities[i].pressure;
    }
  }
}

void MassSpring::DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) {
  const Index n = num_nodes();
  if (id == mech_.position) {
    positions_ = in;
    state_.x.head(3 * n) = Eigen::Map<const VecX>(positions_.data(), 3 * n);
  } else if (id == mech_.velocity) {
    Eigen::Map<Points>(state_.x.data() + 3 * n, 3, n) = in;
  } else if (id == mech_.external_force) {
    state_.external_force = in;
  } else if (id == f_fibre_) {
    Points& fibres = state_.fibres.Write();
    for (Index e = 0; e < fibres.cols(); ++e) {
      const Vec3 f = in.col(e);
      if (f.squaredNorm() > 0 && f.allFinite()) fibres.col(e) = f.normalized();
    }
    UpdateActiveWeights();  // allocates: fibres are set up before a run, not per step
  } else if (id == f_nodal_active_) {
    state_.nodal_active_tension = in.row(0).transpose();
    any_active_ = (state_.nodal_active_tension.array() != 0).any();
  } else {
    // A coupled cavity's pressure is solved each step; writes to it are ignored.
    for (std::size_t i = 0; i < cavities_.size(); ++i)
      if (id == cavities_[i].f_pressure && cavities_[i].law == nullptr)
        state_.cavities[i].pressure = in(0, 0);
  }
}

}  // namespace gipsi
