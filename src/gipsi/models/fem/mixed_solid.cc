#include "gipsi/models/fem/mixed_solid.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include <fmt/format.h>
#include <Eigen/LU>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/base/state.h"
#include "gipsi/geometry/quality.h"
#include "gipsi/models/fem/fem_geometry.h"
#include "gipsi/models/fem/solid_laws.h"

namespace gipsi {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
/// Aspect ratio (CheckTetQuality: 1 regular) above which the constructor warns of a sliver.
constexpr double kSliverAspect = 6;

/// Sorted, unique.
void SortUnique(std::vector<int>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

}  // namespace

MixedSolid::MixedSolid(std::string name, std::shared_ptr<const Mesh> domain,
                       MixedSolidParams params)
    : SimObject(std::move(name)), params_(std::move(params)) {
  if (!params_.material)
    throw InputError(fmt::format("object '{}': MixedSolid needs a material", this->path()));
  law_ = params_.material.get();
  kappa_ = law_->log_volumetric_modulus();
  if (!(kappa_ > 0))
    throw InputError(fmt::format(
        "object '{}': law '{}' has no volumetric term κ/2 (ln J)² for the mixed pressure to "
        "replace; MixedSolid takes \"NeoHookean\" or \"Guccione\"",
        this->path(), law_->law()));
  if (params_.fibre.norm() == 0)
    throw InputError(fmt::format("object '{}': the fibre direction is zero", this->path()));
  if (!(params_.density > 0) || !std::isfinite(params_.density))
    throw InputError(fmt::format("object '{}': the density must be positive, not {}", this->path(),
                                 params_.density));
  if (dynamic() && params_.load_steps != 1)
    throw InputError(fmt::format(
        "object '{}': load_steps {} with a dynamic scheme: a dynamic step is one solve at the "
        "step's loads (make the time step smaller instead)",
        this->path(), params_.load_steps));
  mesh_ = ElevateToQuadratic(*domain);
  state_.axes.Write().assign(static_cast<std::size_t>(kQuad * mesh_.num_elements()),
                             MaterialAxes(params_.fibre, params_.sheet));
  state_.active_prev = VecX::Zero(mesh_.num_elements());
  state_.active_new = VecX::Zero(mesh_.num_elements());
  SetGeometry(domain, MakeBoundary(*domain));

  // Element geometry: P2 gradients and volume weights at the quadrature points.
  const Index ne = mesh_.num_elements();
  const TetQuadrature& rule = TetRuleDegree2();
  weight_.resize(ne * kQuad);
  grad_.resize(static_cast<std::size_t>(ne) * kQuad * 30);
  for (Index e = 0; e < ne; ++e) {
    Mat3 dm;
    for (int k = 0; k < 3; ++k)
      dm.col(k) = mesh_.rest.col(mesh_.elements(k + 1, e)) - mesh_.rest.col(mesh_.elements(0, e));
    const double det = dm.determinant();
    if (!(det > 0))
      throw InputError(
          fmt::format("object '{}': {} is degenerate or inverted (rest "
                      "volume {:.3g} m³)",
                      this->path(), domain->TetName(e), det / 6));
    if (mesh_.IsCurved(e)) {
      CurvedElementGeometry(e, *domain);
      continue;
    }
    const Mat3 inv = dm.inverse();
    Eigen::Matrix<double, 3, 4> gl;
    gl.rightCols<3>() = inv.transpose();
    gl.col(0) = -gl.rightCols<3>().rowwise().sum();
    for (int q = 0; q < kQuad; ++q) {
      const Eigen::Matrix<double, 3, 10> g =
          gl * QuadraticTetShapeDerivatives(rule.points[static_cast<std::size_t>(q)]).transpose();
      Eigen::Map<Eigen::Matrix<double, 3, 10>>(grad_.data() +
                                               (static_cast<std::size_t>(e) * kQuad + q) * 30) = g;
      weight_[e * kQuad + q] = det / 6 * rule.weights[static_cast<std::size_t>(q)];
    }
  }
  // Dynamics and gravity: the consistent mass of every element, exact also for curved ones
  // (N_a N_b det J is of degree 4 + 3).
  const bool needs_mass = dynamic() || params_.gravity.squaredNorm() > 0;
  if (needs_mass) {
    const TetQuadrature& mass_rule = TetRuleDegree7();
    mass_.assign(static_cast<std::size_t>(ne) * 100, 0.0);
    for (Index e = 0; e < ne; ++e) {
      Eigen::Matrix<double, 3, 10> x;
      for (int a = 0; a < 10; ++a) x.col(a) = mesh_.rest.col(mesh_.elements(a, e));
      Eigen::Map<Eigen::Matrix<double, 10, 10>> m(mass_.data() + static_cast<std::size_t>(e) * 100);
      for (std::size_t q = 0; q < mass_rule.points.size(); ++q) {
        const Eigen::Vector4d& l = mass_rule.points[q];
        // dX/dξ for the reference coordinates ξ_k = L_{k+1} (L_0 = 1 − Σ ξ).
        const Eigen::Matrix<double, 10, 4> dl = QuadraticTetShapeDerivatives(l);
        const Eigen::Matrix<double, 10, 3> dxi = dl.rightCols<3>().colwise() - dl.col(0);
        const double det = (x * dxi).determinant();  // 6 × the volume for a straight tet
        const Eigen::Matrix<double, 10, 1> n = QuadraticTetShape(l);
        m.noalias() += (params_.density * mass_rule.weights[q] * det / 6) * (n * n.transpose());
      }
    }
    Points ones(3, mesh_.num_nodes());
    ones.colwise() = params_.gravity;
    gravity_force_ = Eigen::Map<const VecX>(ApplyMass(ones).data(), 3 * mesh_.num_nodes());
  }
  // Slivers: the mixed element's pressure is continuous and linear, so a flat tet can change
  // volume while its neighbours make up for it, at little cost in energy; on Gmsh's 2 mm Land
  // ventricle one tet of aspect 8.3 (the others below 4) collapsed to J = 0.8 at 1 kPa and
  // stopped the solve.
  const TetQualityReport quality = CheckTetQuality(domain->nodes, domain->tets);
  if (quality.max_aspect > kSliverAspect)
    Log().warn(
        "{}: {} has aspect ratio {:.3g} (1 for a regular tet): mixed P2-P1 elements can "
        "collapse in such slivers under load; remesh (or refine) if a step fails there "
        "(docs/incompressible.md)",
        this->path(), domain->TetName(quality.worst_aspect_tet), quality.max_aspect);
  double edge_sum = 0;
  for (Index k = 0; k < mesh_.edges.cols(); ++k)
    edge_sum += (mesh_.rest.col(mesh_.edges(0, k)) - mesh_.rest.col(mesh_.edges(1, k))).norm();
  const double h = edge_sum / static_cast<double>(std::max<Index>(mesh_.edges.cols(), 1));
  pressure_scale_ = law_->small_strain_youngs_modulus() / h;
  diag_scale_ = law_->small_strain_youngs_modulus() * h;

  // Boundary faces as 6-node triangles, each with its tet's local numbering of its nodes.
  const BoundarySurface& bnd = boundary();
  faces_.resize(6, bnd.num_triangles());
  face_local_.resize(6, bnd.num_triangles());
  for (Index f = 0; f < bnd.num_triangles(); ++f) {
    int v[3];
    for (int i = 0; i < 3; ++i)
      v[i] = bnd.vertex_to_node[static_cast<std::size_t>(bnd.triangles(i, f))];
    for (int i = 0; i < 3; ++i) faces_(i, f) = v[i];
    for (int k = 0; k < 3; ++k)
      faces_(3 + k, f) = mesh_.EdgeNode(v[kTriangleEdges[k][0]], v[kTriangleEdges[k][1]]);
    // Where the face's nodes sit in its tet: the load tangent scatters through that tet.
    const Index tet = bnd.face_to_tet[static_cast<std::size_t>(f)];
    for (int a = 0; a < 6; ++a) {
      face_local_(a, f) = -1;
      for (int m = 0; m < 10; ++m)
        if (mesh_.elements(m, tet) == faces_(a, f)) face_local_(a, f) = m;
      GIPSI_CHECK(face_local_(a, f) >= 0, "MixedSolid: boundary face {} is not a face of tet {}", f,
                  tet);
    }
  }

  MakeCurvedDisplay();

  // Sparsity: unknowns 3·node + i (displacements), then 3·nodes + vertex (pressures).
  const Index nn = mesh_.num_nodes();
  const Index nv = mesh_.num_vertices;
  const Index nu = 3 * nn;
  std::vector<std::vector<int>> node_nbrs(static_cast<std::size_t>(nn));
  std::vector<std::vector<int>> vertex_nbrs(static_cast<std::size_t>(nn));
  for (Index e = 0; e < ne; ++e)
    for (int a = 0; a < 10; ++a) {
      auto& nodes = node_nbrs[static_cast<std::size_t>(mesh_.elements(a, e))];
      auto& verts = vertex_nbrs[static_cast<std::size_t>(mesh_.elements(a, e))];
      for (int b = 0; b < 10; ++b) nodes.push_back(mesh_.elements(b, e));
      for (int b = 0; b < 4; ++b) verts.push_back(mesh_.elements(b, e));
    }
  for (auto& v : node_nbrs) SortUnique(v);
  for (auto& v : vertex_nbrs) SortUnique(v);
  const Index n = nu + nv;
  std::vector<int> col_start(static_cast<std::size_t>(n) + 1, 0), rows;
  for (Index c = 0; c < n; ++c) {
    const auto node = static_cast<std::size_t>(c < nu ? c / 3 : c - nu);
    for (int b : node_nbrs[node])
      for (int i = 0; i < 3; ++i) rows.push_back(3 * b + i);
    for (int b : vertex_nbrs[node]) rows.push_back(static_cast<int>(nu) + b);
    col_start[static_cast<std::size_t>(c) + 1] = static_cast<int>(rows.size());
  }
  jac_.resize(n, n);
  jac_.resizeNonZeros(static_cast<Index>(rows.size()));
  std::copy(col_start.begin(), col_start.end(), jac_.outerIndexPtr());
  std::copy(rows.begin(), rows.end(), jac_.innerIndexPtr());
  std::fill(jac_.valuePtr(), jac_.valuePtr() + rows.size(), 0.0);
  auto position = [&](int row, int col) {
    const int* begin = rows.data() + col_start[static_cast<std::size_t>(col)];
    const int* end = rows.data() + col_start[static_cast<std::size_t>(col) + 1];
    const int* it = std::lower_bound(begin, end, row);
    GIPSI_CHECK(it != end && *it == row, "MixedSolid pattern lacks ({}, {})", row, col);
    return static_cast<int>(it - rows.data());
  };
  element_value_index_.resize(static_cast<std::size_t>(ne) * kLocal * kLocal);
  for (Index e = 0; e < ne; ++e) {
    int dof[kLocal];
    for (int a = 0; a < 10; ++a)
      for (int i = 0; i < 3; ++i) dof[3 * a + i] = 3 * mesh_.elements(a, e) + i;
    for (int b = 0; b < 4; ++b) dof[30 + b] = static_cast<int>(nu) + mesh_.elements(b, e);
    int* out = element_value_index_.data() + static_cast<std::size_t>(e) * kLocal * kLocal;
    for (int c = 0; c < kLocal; ++c)
      for (int r = 0; r < kLocal; ++r) out[c * kLocal + r] = position(dof[r], dof[c]);
  }
  diag_index_.resize(static_cast<std::size_t>(n));
  for (Index c = 0; c < n; ++c)
    diag_index_[static_cast<std::size_t>(c)] = position(static_cast<int>(c), static_cast<int>(c));

  constrained_.assign(static_cast<std::size_t>(nu), 0);
  target_prev_ = VecX::Zero(nu);
  target_new_ = VecX::Zero(nu);
  state_.force_prev = VecX::Zero(3 * nv);
  force_new_ = VecX::Zero(3 * nv);
  state_.pressure_prev = VecX::Zero(bnd.num_triangles());
  pressure_new_ = VecX::Zero(bnd.num_triangles());
  state_.traction_prev = Points::Zero(3, bnd.num_triangles());
  traction_new_ = Points::Zero(3, bnd.num_triangles());
  state_.external_force.Write() = Points::Zero(3, nv);
  state_.z = VecX::Zero(n);
  z_begin_ = state_.z;
  vertex_positions_ = domain->nodes;

  std::unique_ptr<LinearSolver> linear;
  if (params_.linear_solver.type == "schur_gmres") {
    linear = MakeSchurSolver();
  } else {
    linear = MakeLinearSolver(params_.linear_solver);
  }
  linear->AcceptIndefinite();
  // UMFPACK's LU and GMRES take the exact, nonsymmetric load tangent.
  exact_load_tangent_ = linear->name() == "umfpack" || linear->name() == "schur_gmres";
  newton_ = std::make_unique<NewtonSolver>(params_.newton, std::move(linear));
  newton_->Prepare(jac_);

  using L = FieldLocation;
  using A = FieldAccess;
  mech_ = DeclareMechanicalFields();
  f_pressure_ = DeclareField({"pressure", L::kNode, 1, "Pa", A::kRead,
                              "hydrostatic pressure of the mixed formulation (p = κ ln J)"});
  f_jacobian_ = DeclareField({"volume_ratio", L::kElement, 1, "1", A::kRead,
                              "volume ratio J = det F, mean over the element's quadrature points"});
  f_fibre_ = DeclareField(
      {"fibre", L::kElement, 3, "1", A::kReadWrite, "fibre direction (reference configuration)"});
  f_active_ = DeclareField({"active_tension", L::kElement, 1, "Pa", A::kReadWrite,
                            "active tension along the fibre (second Piola-Kirchhoff); a step "
                            "ramps it from the previous step's value with the loads"});
  f_volume_ = DeclareField({"volume", L::kGlobal, 1, "m^3", A::kRead, "current volume ∫ J dV"});
  f_energy_ = DeclareField({"strain_energy", L::kGlobal, 1, "J", A::kRead,
                            "stored elastic energy (the law's; without the volumetric term when "
                            "incompressible)"});
  f_newton_ = DeclareField({"newton_iterations", L::kGlobal, 1, "1", A::kRead,
                            "Newton iterations of the last load increment"});
  f_kinetic_ = DeclareField({"kinetic_energy", L::kGlobal, 1, "J", A::kRead,
                             "1/2 v' M v over the P2 nodes (0 when quasi-static)"});
  MakeCavities(*domain);
  state_.scheme = ImplicitScheme(params_.scheme);
  if (dynamic()) {
    const VecX zero = VecX::Zero(nu);
    state_.scheme.Reset(zero, zero, zero);
  }
  BindState(state_);
}

Points MixedSolid::NodeDisplacements() const {
  return Eigen::Map<const Points>(state_.z.data(), 3, mesh_.num_nodes());
}

VecX MixedSolid::Pressures() const { return pressure_scale_ * state_.z.tail(mesh_.num_vertices); }

Points MixedSolid::ApplyMass(const Points& x) const {
  GIPSI_CHECK(x.cols() == mesh_.num_nodes() && !mass_.empty(),
              "MixedSolid::ApplyMass: a field of {} nodes, or no mass (quasi-static, no gravity)",
              x.cols());
  Points y = Points::Zero(3, mesh_.num_nodes());
  for (Index e = 0; e < mesh_.num_elements(); ++e) {
    const Eigen::Map<const Eigen::Matrix<double, 10, 10>> m(mass_.data() +
                                                            static_cast<std::size_t>(e) * 100);
    for (int b = 0; b < 10; ++b) {
      const Vec3 xb = x.col(mesh_.elements(b, e));
      for (int a = 0; a < 10; ++a) y.col(mesh_.elements(a, e)) += m(a, b) * xb;
    }
  }
  return y;
}

Points MixedSolid::NodeVelocities() const {
  if (!dynamic()) return Points::Zero(3, mesh_.num_nodes());
  return Eigen::Map<const Points>(state_.scheme.v().data(), 3, mesh_.num_nodes());
}

void MixedSolid::AssembleInertia(const VecX& z, VecX& r, double* jv) const {
  const ImplicitScheme& scheme = state_.scheme;
  const double alpha = params_.rayleigh_mass;
  const double c_a = scheme.c_a(), c_v = scheme.c_v();
  const VecX& x_n = scheme.x();
  const VecX& a_hat = scheme.a_hat();
  const VecX& v_hat = scheme.v_hat();
  for (Index e = 0; e < mesh_.num_elements(); ++e) {
    const Eigen::Map<const Eigen::Matrix<double, 10, 10>> m(mass_.data() +
                                                            static_cast<std::size_t>(e) * 100);
    for (int b = 0; b < 10; ++b) {
      const Index db = 3 * mesh_.elements(b, e);
      // a + α v of node b: both affine in its increment d = u − x_n.
      const Vec3 d = z.segment<3>(db) - x_n.segment<3>(db);
      const Vec3 w = (c_a * d + a_hat.segment<3>(db)) + alpha * (c_v * d + v_hat.segment<3>(db));
      for (int a = 0; a < 10; ++a) r.segment<3>(3 * mesh_.elements(a, e)) += m(a, b) * w;
    }
    if (jv == nullptr) continue;
    const int* idx = element_value_index_.data() + static_cast<std::size_t>(e) * kLocal * kLocal;
    const double c = c_a + alpha * c_v;
    for (int b = 0; b < 10; ++b)
      for (int a = 0; a < 10; ++a)
        for (int i = 0; i < 3; ++i) jv[idx[(3 * b + i) * kLocal + 3 * a + i]] += c * m(a, b);
  }
}

Mat3 MixedSolid::DeformationGradient(Index e, int q, const VecX& z) const {
  const auto g = Eigen::Map<const Eigen::Matrix<double, 3, 10>>(
      grad_.data() + (static_cast<std::size_t>(e) * kQuad + q) * 30);
  Mat3 F = Mat3::Identity();
  for (int a = 0; a < 10; ++a)
    F.noalias() += z.segment<3>(3 * mesh_.elements(a, e)) * g.col(a).transpose();
  return F;
}

void MixedSolid::CurvedElementGeometry(Index e, const Mesh& domain) {
  // Isoparametric map x(ξ) = Σ_a X_a N_a(ξ), ξ = (L_1, L_2, L_3): its Jacobian D = ∂x/∂ξ
  // varies over the element; ∇N_a = D⁻ᵀ ∂N_a/∂ξ and dV = det D / 6 × the rule's weight.
  Eigen::Matrix<double, 3, 10> x;
  for (int a = 0; a < 10; ++a) x.col(a) = mesh_.rest.col(mesh_.elements(a, e));
  auto reference_derivatives = [](const Eigen::Vector4d& L) {
    const Eigen::Matrix<double, 10, 4> d = QuadraticTetShapeDerivatives(L);
    Eigen::Matrix<double, 10, 3> dxi;
    for (int k = 0; k < 3; ++k) dxi.col(k) = d.col(k + 1) - d.col(0);
    return dxi;
  };
  auto fail = [&](double det, const std::string& where) {
    throw InputError(fmt::format(
        "object '{}': {} is curved too much: the Jacobian of its map from the reference tet is "
        "{:.3g} at {} (it must be positive throughout the element); move its edges' middle "
        "nodes closer to the midpoints, or refine the mesh where the surface curves",
        this->path(), domain.TetName(e), det, where));
  };
  // Where the Jacobian is most often lowest: the corners (the quadrature points follow).
  for (int a = 0; a < 4; ++a) {
    const double det = (x * reference_derivatives(Eigen::Vector4d::Unit(a))).determinant();
    if (!(det > 0)) fail(det, fmt::format("its corner {}", a));
  }
  const TetQuadrature& rule = TetRuleDegree2();
  for (int q = 0; q < kQuad; ++q) {
    const Eigen::Matrix<double, 10, 3> dxi =
        reference_derivatives(rule.points[static_cast<std::size_t>(q)]);
    const Mat3 jacobian = x * dxi;
    const double det = jacobian.determinant();
    if (!(det > 0)) fail(det, fmt::format("its quadrature point {}", q));
    Eigen::Map<Eigen::Matrix<double, 3, 10>>(grad_.data() +
                                             (static_cast<std::size_t>(e) * kQuad + q) * 30) =
        jacobian.inverse().transpose() * dxi.transpose();
    weight_[e * kQuad + q] = det / 6 * rule.weights[static_cast<std::size_t>(q)];
  }
}

double MixedSolid::CurrentVolume() const {
  // The deformed body's volume exactly: x is quadratic on the reference tet (curved or not),
  // so det ∂x/∂ξ is a cubic, which the degree-7 rule integrates exactly. (The stiffness's
  // 4-point rule is not exact for it; near incompressibility, where J varies about 1 inside a
  // tet while ln J vanishes on average, it would add ½ ∫ (ln J)² dV.)
  static const std::vector<Eigen::Matrix<double, 10, 4>> kDerivatives = [] {
    std::vector<Eigen::Matrix<double, 10, 4>> d;
    for (const Eigen::Vector4d& point : TetRuleDegree7().points)
      d.push_back(QuadraticTetShapeDerivatives(point));
    return d;
  }();
  const std::vector<double>& weights = TetRuleDegree7().weights;
  double v = 0;
  for (Index e = 0; e < mesh_.num_elements(); ++e) {
    Eigen::Matrix<double, 3, 10> x;
    for (int a = 0; a < 10; ++a) {
      const Index node = mesh_.elements(a, e);
      x.col(a) = mesh_.rest.col(node) + state_.z.segment<3>(3 * node);
    }
    double element = 0;
    for (std::size_t q = 0; q < weights.size(); ++q) {
      const Eigen::Matrix<double, 10, 4>& d = kDerivatives[q];
      Mat3 dx;  // ∂x/∂ξ_k with ξ = (L_1, L_2, L_3), L_0 = 1 − Σ ξ
      for (int k = 0; k < 3; ++k) dx.col(k) = x * (d.col(k + 1) - d.col(0));
      element += weights[q] * dx.determinant();
    }
    v += element / 6;
  }
  return v;
}

void MixedSolid::SetFibreAt(Index e, int q, const Vec3& fibre) {
  GIPSI_CHECK(e >= 0 && e < mesh_.num_elements() && q >= 0 && q < kQuad && fibre.norm() > 0,
              "MixedSolid::SetFibreAt({}, {}): no such point or a zero fibre", e, q);
  Mat3& axes = state_.axes.Write()[static_cast<std::size_t>(kQuad * e + q)];
  axes = MaterialAxes(fibre, axes.col(1));
}

Vec3 MixedSolid::QuadraturePoint(Index e, int q) const {
  GIPSI_CHECK(e >= 0 && e < mesh_.num_elements() && q >= 0 && q < kQuad,
              "MixedSolid::QuadraturePoint({}, {}): no such point", e, q);
  const Eigen::Matrix<double, 10, 1> n =
      QuadraticTetShape(TetRuleDegree2().points[static_cast<std::size_t>(q)]);
  Vec3 x = Vec3::Zero();
  for (int a = 0; a < 10; ++a) x += n[a] * mesh_.rest.col(mesh_.elements(a, e));
  return x;
}

const Mat3& MixedSolid::axes_at(Index e, int q) const {
  return state_.axes.get()[static_cast<std::size_t>(kQuad * e + q)];
}

MaterialPoint MixedSolid::PointOf(Index e, int q, double load) const {
  MaterialPoint mp;
  mp.axes = state_.axes.get()[static_cast<std::size_t>(kQuad * e + q)];
  mp.active_tension = (1 - load) * state_.active_prev[e] + load * state_.active_new[e];
  return mp;
}

double MixedSolid::ElementEnergy(Index e, const VecX& z) const {
  double w = 0;
  for (int q = 0; q < kQuad; ++q) {
    const MaterialPoint mp = PointOf(e, q, 1.0);
    const Mat3 F = DeformationGradient(e, q, z);
    double energy = law_->Energy(F, mp);
    if (params_.incompressible && std::isfinite(energy)) {
      const double log_j = std::log(F.determinant());
      energy -= 0.5 * kappa_ * log_j * log_j;
    }
    w += weight_[e * kQuad + q] * energy;
  }
  return w;
}

bool MixedSolid::Assemble(const VecX& z, double load, VecX& r, double* jv) const {
  const Index nu = 3 * mesh_.num_nodes();
  const TetQuadrature& rule = TetRuleDegree2();
  const double s = pressure_scale_;
  const double inv_kappa = params_.incompressible ? 0.0 : 1.0 / kappa_;
  r.setZero(z.size());
  if (jv != nullptr) std::fill(jv, jv + jac_.nonZeros(), 0.0);
  if (jv != nullptr && saddle_ != nullptr)
    std::fill(augmentation_.begin(), augmentation_.end(), 0.0);
  double floor_sq = 0;
  Mat3 P;
  Mat9 C;
  for (Index e = 0; e < mesh_.num_elements(); ++e) {
    Eigen::Matrix<double, 3, 10> u;
    for (int a = 0; a < 10; ++a) u.col(a) = z.segment<3>(3 * mesh_.elements(a, e));
    Eigen::Vector4d pe;
    for (int b = 0; b < 4; ++b) pe[b] = z[nu + mesh_.elements(b, e)];
    Eigen::Matrix<double, kLocal, 1> re = Eigen::Matrix<double, kLocal, 1>::Zero();
    Eigen::Matrix<double, kLocal, kLocal> ke;
    if (jv != nullptr) ke.setZero();
    double floor_e = 0;  // magnitude of the terms that cancel in this element's residual
    double shear = 0;
    Eigen::Matrix<double, 30, 30> augment;
    if (jv != nullptr && saddle_ != nullptr) augment.setZero();
    for (int q = 0; q < kQuad; ++q) {
      const auto g = Eigen::Map<const Eigen::Matrix<double, 3, 10>>(
          grad_.data() + (static_cast<std::size_t>(e) * kQuad + q) * 30);
      const Eigen::Vector4d& lq = rule.points[static_cast<std::size_t>(q)];
      const double w = weight_[e * kQuad + q];
      const MaterialPoint mp = PointOf(e, q, load);
      const Mat3 F = Mat3::Identity() + u * g.transpose();
      const double J = F.determinant();
      if (!(J > kMinJacobian)) return false;
      const bool ok = jv != nullptr ? law_->StressAndTangent(F, mp, P, C) : law_->Stress(F, mp, P);
      if (!ok) return false;
      const Mat3 H = F.inverse().transpose();
      const double log_j = std::log(J);
      const double p = s * lq.dot(pe);
      // The law's volumetric stress κ ln J H is replaced by the independent pressure's p H.
      const Mat3 Pm = P + (p - kappa_ * log_j) * H;
      const Eigen::Matrix<double, 3, 10> f = w * Pm * g;  // nodal forces f_a = w Pm ∇N_a
      // The law's stress and the volumetric stress it carries are formed and cancelled in
      // double precision; ln J itself is known to a few ulps, which κ amplifies.
      floor_e += w * g.norm() * (P.norm() + (std::abs(kappa_ * log_j) + 4 * kappa_ * kEps));
      for (int a = 0; a < 10; ++a) re.segment<3>(3 * a) += f.col(a);
      re.tail<4>() += (w * s * (log_j - p * inv_kappa)) * lq;
      if (jv == nullptr) continue;
      // dPm/dF = dP/dF − κ H_ij H_kl + (κ ln J − p) H_il H_kj (∂H_ij/∂F_kl = −H_il H_kj).
      const double c2 = kappa_ * log_j - p;
      for (int l = 0; l < 3; ++l)
        for (int k = 0; k < 3; ++k)
          for (int j = 0; j < 3; ++j)
            for (int i = 0; i < 3; ++i)
              C(i + 3 * j, k + 3 * l) += -kappa_ * H(i, j) * H(k, l) + c2 * H(i, l) * H(k, j);
      // The element's effective shear modulus for the Schur approximation: Σ ∂P_ij/∂F_ij / 12
      // (μ for an isotropic deviatoric law at rest), from the tangent without its κ term.
      if (saddle_ != nullptr) {
        const double mu_q = std::max(C.diagonal().sum() / 12, 0.01 * rest_shear_);
        shear += mu_q / kQuad;
        // The preconditioner's augmentation γ ∫ (H : ∇N_a)(H : ∇N_b), γ = μ_q: positive on the
        // volume-changing motions that the pressure's own terms may leave indefinite.
        const Eigen::Matrix<double, 3, 10> hg = H * g;
        const Eigen::Map<const Eigen::Matrix<double, 30, 1>> d(hg.data());
        augment.noalias() += (w * mu_q) * (d * d.transpose());
      }
      for (int b = 0; b < 10; ++b) {
        Eigen::Matrix<double, 9, 3> t;
        for (int k = 0; k < 3; ++k)
          t.col(k) = C.col(k) * g(0, b) + C.col(k + 3) * g(1, b) + C.col(k + 6) * g(2, b);
        for (int a = 0; a < 10; ++a)
          ke.block<3, 3>(3 * a, 3 * b) +=
              w * (g(0, a) * t.block<3, 3>(0, 0) + g(1, a) * t.block<3, 3>(3, 0) +
                   g(2, a) * t.block<3, 3>(6, 0));
      }
      const Eigen::Matrix<double, 3, 10> hg = H * g;  // ∂ ln J / ∂u_a = H ∇N_a
      for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 10; ++a) {
          const Vec3 coupling = (w * s * lq[b]) * hg.col(a);
          ke.block<3, 1>(3 * a, 30 + b) += coupling;
          ke.block<1, 3>(30 + b, 3 * a) += coupling.transpose();
        }
      ke.bottomRightCorner<4, 4>() -= (w * s * s * inv_kappa) * (lq * lq.transpose());
    }
    floor_sq += floor_e * floor_e;
    if (jv != nullptr && saddle_ != nullptr) {
      element_shear_[e] = shear;
      const int* idx = element_value_index_.data() + static_cast<std::size_t>(e) * kLocal * kLocal;
      for (int c = 0; c < 30; ++c)
        for (int rr = 0; rr < 30; ++rr) augmentation_[idx[c * kLocal + rr]] += augment(rr, c);
    }
    for (int a = 0; a < 10; ++a) r.segment<3>(3 * mesh_.elements(a, e)) += re.segment<3>(3 * a);
    for (int b = 0; b < 4; ++b) r[nu + mesh_.elements(b, e)] += re[30 + b];
    if (jv == nullptr) continue;
    const int* idx = element_value_index_.data() + static_cast<std::size_t>(e) * kLocal * kLocal;
    for (int c = 0; c < kLocal; ++c)
      for (int rr = 0; rr < kLocal; ++rr) jv[idx[c * kLocal + rr]] += ke(rr, c);
  }
  // Round-off of the assembled residual: a few ulps of the element terms that cancel in it.
  residual_floor_ = 16 * kEps * std::sqrt(floor_sq);
  return true;
}

void MixedSolid::AssembleLoads(const VecX& z, double s, VecX& r, double* jv) const {
  const Index nv = mesh_.num_vertices;
  // Gravity: in full from the first dynamic step; ramped in from the first quasi-static one.
  if (gravity_force_.size() > 0)
    r.head(gravity_force_.size()) -= (dynamic() || state_.have_prev ? 1.0 : s) * gravity_force_;
  for (Index v = 0; v < nv; ++v)
    r.segment<3>(3 * v) -=
        (1 - s) * state_.force_prev.segment<3>(3 * v) + s * force_new_.segment<3>(3 * v);
  const TriangleQuadrature& rule = TriangleRuleDegree4();
  const BoundarySurface& bnd = boundary();
  for (Index f = 0; f < faces_.cols(); ++f) {
    const double p = (1 - s) * state_.pressure_prev[f] + s * pressure_new_[f];
    const Vec3 t = (1 - s) * state_.traction_prev.col(f) + s * traction_new_.col(f);
    if (p == 0 && t.isZero()) continue;
    Eigen::Matrix<double, 3, 6> x;
    for (int a = 0; a < 6; ++a)
      x.col(a) = mesh_.rest.col(faces_(a, f)) + z.segment<3>(3 * faces_(a, f));
    Eigen::Matrix<double, 3, 6> load = Eigen::Matrix<double, 3, 6>::Zero();
    Eigen::Matrix<double, 18, 18> k = Eigen::Matrix<double, 18, 18>::Zero();
    for (std::size_t q = 0; q < rule.points.size(); ++q) {
      const auto n_shape = QuadraticTriangleShape(rule.points[q]);
      const auto dn = QuadraticTriangleParamDerivatives(rule.points[q]);
      const Vec3 xi = x * dn.col(0), eta = x * dn.col(1);
      const Vec3 normal = xi.cross(eta);  // outward, |normal| = area per reference area
      const double area = normal.norm();
      const double w = 0.5 * rule.weights[q];  // the reference triangle's area is 1/2
      const Vec3 density = -p * normal + area * t;
      for (int a = 0; a < 6; ++a) load.col(a) += (w * n_shape[a]) * density;
      if (jv == nullptr) continue;
      const Vec3 unit = area > 0 ? Vec3(normal / area) : Vec3::Zero();
      for (int b = 0; b < 6; ++b) {
        const Mat3 dnormal = -CrossMatrix(eta) * dn(b, 0) + CrossMatrix(xi) * dn(b, 1);
        const Mat3 ddensity = -p * dnormal + t * (unit.transpose() * dnormal);
        for (int a = 0; a < 6; ++a) k.block<3, 3>(3 * a, 3 * b) += (w * n_shape[a]) * ddensity;
      }
    }
    for (int a = 0; a < 6; ++a) r.segment<3>(3 * faces_(a, f)) -= load.col(a);
    if (jv == nullptr) continue;
    // J −= sym(∂f_ext/∂x), through the face's tet (every face pair is a pair of that tet).
    const Index tet = bnd.face_to_tet[static_cast<std::size_t>(f)];
    const auto local = face_local_.col(f);
    // The exact load tangent is not symmetric; the symmetric solvers get its symmetric part
    // (Newton then converges linearly: in a slender body under follower pressure, such as the
    // Land beam, the dropped part is of the order of the softest bending stiffness).
    const Eigen::Matrix<double, 18, 18> sym =
        exact_load_tangent_ ? Eigen::Matrix<double, 18, 18>(k)
                            : Eigen::Matrix<double, 18, 18>(0.5 * (k + k.transpose()));
    const int* idx = element_value_index_.data() + static_cast<std::size_t>(tet) * kLocal * kLocal;
    for (int b = 0; b < 6; ++b)
      for (int kk = 0; kk < 3; ++kk)
        for (int a = 0; a < 6; ++a)
          for (int i = 0; i < 3; ++i)
            jv[idx[(3 * local[b] + kk) * kLocal + 3 * local[a] + i]] -= sym(3 * a + i, 3 * b + kk);
  }
}

void MixedSolid::ApplyConstraints(VecX& r, double* jv) const {
  for (int dof : constrained_dofs_) r[dof] = 0;
  if (jv == nullptr || constrained_dofs_.empty()) return;
  const Index nu = 3 * mesh_.num_nodes();
  for (Index c = 0; c < jac_.outerSize(); ++c) {
    const bool col_held = c < nu && constrained_[static_cast<std::size_t>(c)] != 0;
    for (int k = jac_.outerIndexPtr()[c]; k < jac_.outerIndexPtr()[c + 1]; ++k) {
      const int row = jac_.innerIndexPtr()[k];
      if (!col_held && !(row < nu && constrained_[static_cast<std::size_t>(row)] != 0)) continue;
      jv[k] = 0;
      if (saddle_ != nullptr) augmentation_[static_cast<std::size_t>(k)] = 0;
    }
  }
  for (int dof : constrained_dofs_) jv[diag_index_[static_cast<std::size_t>(dof)]] = diag_scale_;
}

/// One load increment as the nonlinear system r(z) = 0 that Newton solves: its inputs are its
/// arguments, the load fraction s (loads, active tension and constraint targets interpolated
/// between the step's start, 0, and end, 1) and the force scale of the convergence test (the
/// applied loads at s).
class MixedSolid::Increment final : public NonlinearSystem {
 public:
  Increment(MixedSolid& solid, double s, double force_scale)
      : solid_(solid), s_(s), force_scale_(force_scale) {}
  bool CalcResidual(const VecX& z, VecX& r) override {
    return solid_.IncrementResidual(s_, z, r, nullptr);
  }
  bool CalcResidualAndJacobian(const VecX& z, VecX& r, SparseMatrix& J) override {
    return solid_.IncrementResidual(s_, z, r, J.valuePtr());
  }
  [[nodiscard]] double force_scale() const override { return force_scale_; }
  [[nodiscard]] double residual_floor() const override { return solid_.residual_floor_; }
  [[nodiscard]] int num_low_rank_terms() const override { return solid_.num_low_rank_terms(); }
  void LowRankTerm(int k, const VecX*& b, double& w) const override { solid_.LowRankTerm(k, b, w); }
  [[nodiscard]] int num_bordered() const override { return solid_.bordered_; }

 private:
  MixedSolid& solid_;
  const double s_;
  const double force_scale_;
};

bool MixedSolid::IncrementResidual(double s, const VecX& x, VecX& r, double* jv) {
  const auto start = std::chrono::steady_clock::now();
  const bool ok = IncrementResidualOnly(s, x, r, jv);
  if (ok && jv != nullptr && saddle_ != nullptr) UpdatePreconditioner();
  assembly_seconds_ +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return ok;
}

std::vector<SimObject::ProfileEntry> MixedSolid::ProfileBreakdown() const {
  return {{"assembly (residual, tangent)", assembly_seconds_, "s"},
          {"linear solves (factorisations included)", newton_seconds_ - assembly_seconds_, "s"},
          {"Newton iterations", static_cast<double>(state_.total_iterations), ""},
          {"linear iterations", static_cast<double>(total_linear_iterations_), ""},
          {"factorisations", static_cast<double>(factorizations_), ""}};
}

bool MixedSolid::IncrementResidualOnly(double s, const VecX& x, VecX& r, double* jv) {
  if (bordered_ == 0) {
    if (!Assemble(x, s, r, jv)) return false;
    if (dynamic()) AssembleInertia(x, r, jv);
    AssembleLoads(x, s, r, jv);
    ApplyConstraints(r, jv);
    return r.allFinite();
  }
  // (z, p): the pressures go to the state, where the cavity loads read them.
  TakeIterate(x);
  const VecX& z = state_.z;
  if (!Assemble(z, s, iterate_r_, jv)) return false;
  if (dynamic()) AssembleInertia(z, iterate_r_, jv);
  AssembleLoads(z, s, iterate_r_, jv);
  if (!AddCavityLoads(z, iterate_r_, jv, true)) return false;
  ApplyConstraints(iterate_r_, jv);
  const Index n = z.size();
  r.head(n) = iterate_r_;
  Index k = n;
  for (const Cavity& cavity : cavities_)
    if (cavity.wall.law != nullptr) r[k++] = cavity.volume_residual;
  return r.allFinite();
}

bool MixedSolid::EvaluateUnconstrained(const VecX& z, double s, VecX& r,
                                       SparseMatrix* jacobian) const {
  if (jacobian != nullptr) *jacobian = jac_;
  double* jv = jacobian != nullptr ? jacobian->valuePtr() : nullptr;
  const bool ok = Assemble(z, s, r, jv);
  if (ok) {
    AssembleLoads(z, s, r, jv);
    AddCavityLoads(z, r, jv, false);  // at the state's pressures
  }
  return ok;
}

Index MixedSolid::GatherLoads() {
  Index velocity_vertex = -1;
  const BoundarySurface& bnd = boundary();
  const BoundaryConditions& bcs = boundary_conditions();
  const Index nv = mesh_.num_vertices;
  for (Index v = 0; v < nv; ++v) force_new_.segment<3>(3 * v) = state_.external_force.get().col(v);
  for (Index j = 0; j < bnd.num_vertices(); ++j)
    force_new_.segment<3>(3 * bnd.vertex_to_node[static_cast<std::size_t>(j)]) += bcs.force(j);
  for (Index f = 0; f < bnd.num_triangles(); ++f) {
    pressure_new_[f] = bcs.pressure(f);
    traction_new_.col(f) = bcs.traction(f);
  }
  for (std::size_t c = 0; c < cavities_.size(); ++c)
    if (cavities_[c].wall.law == nullptr)
      for (int f : cavities_[c].wall.faces)
        pressure_new_[f] += state_.cavity_pressure[static_cast<Index>(c)];
  // Constraints on the vertices; an edge node is held on the axes held at both of its ends,
  // at their mean displacement.
  std::fill(constrained_.begin(), constrained_.end(), 0);
  for (Index j = 0; j < bnd.num_vertices(); ++j) {
    const Index node = bnd.vertex_to_node[static_cast<std::size_t>(j)];
    for (int a = 0; a < 3; ++a) {
      if (bcs.kind(j, a) == ConstraintKind::kFree) continue;
      const Index dof = 3 * node + a;
      if (bcs.kind(j, a) == ConstraintKind::kVelocity) {
        if (!dynamic()) {
          velocity_vertex = j;
          continue;
        }
        // The increment that gives this velocity at the end of the step (Begin has run).
        constrained_[static_cast<std::size_t>(dof)] = 1;
        target_new_[dof] =
            state_.scheme.x()[dof] + state_.scheme.IncrementForVelocity(dof, bcs.value(j)[a]);
        continue;
      }
      constrained_[static_cast<std::size_t>(dof)] = 1;
      target_new_[dof] = bcs.value(j)[a];
    }
  }
  for (Index k = 0; k < mesh_.edges.cols(); ++k) {
    const Index node = mesh_.num_vertices + k;
    for (int a = 0; a < 3; ++a) {
      const auto d0 = static_cast<std::size_t>(3 * mesh_.edges(0, k) + a);
      const auto d1 = static_cast<std::size_t>(3 * mesh_.edges(1, k) + a);
      if (constrained_[d0] == 0 || constrained_[d1] == 0) continue;
      constrained_[static_cast<std::size_t>(3 * node + a)] = 1;
      target_new_[3 * node + a] =
          0.5 * (target_new_[static_cast<Index>(d0)] + target_new_[static_cast<Index>(d1)]);
    }
  }
  constrained_dofs_.clear();
  for (std::size_t d = 0; d < constrained_.size(); ++d)
    if (constrained_[d] != 0) constrained_dofs_.push_back(static_cast<int>(d));
  if (!state_.have_prev) {
    state_.force_prev.setZero();
    state_.pressure_prev.setZero();
    state_.traction_prev.setZero();
  }
  return velocity_vertex;
}

void MixedSolid::SetTargets(VecX& z, double s) const {
  for (int dof : constrained_dofs_) z[dof] = (1 - s) * target_prev_[dof] + s * target_new_[dof];
}

bool MixedSolid::PredictFromTargets(VecX& z, double s) {
  if (dynamic() || bordered_ != 0 || saddle_ != nullptr) return false;
  VecX held = VecX::Zero(z.size());  // the targets' increment on the held dofs
  bool moves = false;
  for (int dof : constrained_dofs_) {
    held[dof] = (1 - s) * target_prev_[dof] + s * target_new_[dof] - z[dof];
    moves = moves || held[dof] != 0;
  }
  if (!moves) return false;
  // A held node moved alone would leave its tets a boundary layer of large strain: near
  // incompressibility, a volume change times κ, a pressure far above the shear modulus under
  // which the P2–P1 tangent is indefinite and Newton wanders (1,900 iterations for a 1 %
  // stretch at κ/C = 10⁵). The tangent at z carries the held increment inward instead:
  //   J_ff Δ_f = −r_f − J_fh Δ_h.
  SparseMatrix jac = jac_;
  VecX r = VecX::Zero(z.size());
  if (!Assemble(z, s, r, jac.valuePtr())) return false;
  AssembleLoads(z, s, r, jac.valuePtr());
  VecX rhs = -(r + jac * held);
  ApplyConstraints(rhs, jac.valuePtr());
  LinearSolver* solver = &newton_->linear_solver();
  if (params_.newton.reuse_factorization) {  // Newton's factorisation is kept: leave it be
    if (predictor_solver_ == nullptr) {
      predictor_solver_ = MakeLinearSolver(params_.linear_solver);
      predictor_solver_->AcceptIndefinite();
      predictor_solver_->AnalyzePattern(jac_);
    }
    solver = predictor_solver_.get();
  }
  VecX delta = VecX::Zero(z.size());
  if (!solver->Factorize(jac) || !solver->Solve(rhs, delta).converged || !delta.allFinite())
    return false;
  const VecX predicted = z + held + delta;
  if (!Assemble(predicted, s, r, nullptr)) return false;
  z = predicted;
  return true;
}

StepStatus MixedSolid::Advance(double s0, double s1, int depth) {
  const int n = depth == 0 ? params_.load_steps : 2;
  for (int k = 1; k <= n; ++k) {
    const double sa = s0 + (s1 - s0) * (k - 1) / n;
    const double sb = k == n ? s1 : s0 + (s1 - s0) * k / n;
    if (stop_token().stop_requested()) return StepStatus::Stopped();
    const VecX z_start = state_.z;
    const VecX p_start = state_.cavity_pressure;
    VecX loads = VecX::Zero(state_.z.size());
    AssembleLoads(state_.z, sb, loads, nullptr);
    AddCavityLoads(state_.z, loads, nullptr, false);  // the pressures of the increment's start
    ApplyConstraints(loads, nullptr);
    const double force_scale = loads.norm();
    auto solve = [&](bool predicted) {
      if (predicted) {  // a dynamic step: one increment, the scheme begun
        PredictIncrement(state_.scheme, params_.predictor, step_dt_, predicted_);
        state_.z.head(predicted_.size()) = state_.scheme.x() + predicted_;
      }
      if (!predicted) PredictFromTargets(state_.z, sb);
      SetTargets(state_.z, sb);
      Increment increment(*this, sb, force_scale);
      const auto start = std::chrono::steady_clock::now();
      if (bordered_ == 0) {
        state_.last_newton = newton_->Solve(increment, state_.z, jac_, stop_token());
      } else {
        GiveIterate(newton_x_);
        state_.last_newton = newton_->Solve(increment, newton_x_, jac_, stop_token());
        TakeIterate(newton_x_);  // the last residual may have been a rejected trial's
      }
      state_.total_iterations += state_.last_newton.iterations;
      total_linear_iterations_ += state_.last_newton.linear_iterations;
      factorizations_ += state_.last_newton.refactorizations;
      newton_seconds_ +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    const bool predict = dynamic() && params_.predictor != StepPredictor::kNone;
    solve(predict);
    if (predict && state_.last_newton.inadmissible && state_.last_newton.iterations == 0) {
      state_.z = z_start;  // the predicted state was not admissible: start from the last one
      state_.cavity_pressure = p_start;
      solve(false);
    }
    if (state_.last_newton.converged) continue;
    state_.z = z_start;
    state_.cavity_pressure = p_start;
    if (state_.last_newton.interrupted) return StepStatus::Stopped();
    if (depth >= params_.max_bisections || dynamic()) {
      failure_detail_ =
          fmt::format("load increment {:.6g} → {:.6g} of the step: {}{}", sa, sb,
                      Describe(state_.last_newton, params_.newton, newton_->linear_solver().name()),
                      MostCompressedElement());
      if (failed_cavity_ >= 0) {
        failure_detail_ += fmt::format(
            "; the blood coupled to cavity '{}' could not give its volume at the wall's "
            "pressure, or its volume does not fall as the pressure rises (is the blood object "
            "stepped right after this one?)",
            params_.cavities[static_cast<std::size_t>(failed_cavity_)].name);
        if (state_.last_newton.inadmissible)
          return StepStatus::Failed("the blood coupled to a cavity could not answer; cavity",
                                    failed_cavity_);
      }
      return StepStatus::Failed(dynamic() ? "Newton did not converge (try a smaller dt)"
                                          : "Newton did not converge (bisections exhausted)");
    }
    const StepStatus status = Advance(sa, sb, depth + 1);
    if (!status.ok()) return status;
  }
  return StepStatus::Ok();
}

std::string MixedSolid::MostCompressedElement() const {
  double smallest = std::numeric_limits<double>::infinity();
  Index worst = -1;
  for (Index e = 0; e < mesh_.num_elements(); ++e)
    for (int q = 0; q < kQuad; ++q) {
      const Mat3 F = DeformationGradient(e, q, state_.z);
      if (const double j = F.determinant(); j < smallest) {
        smallest = j;
        worst = e;
      }
    }
  if (worst < 0) return {};
  Vec3 centre = Vec3::Zero();
  for (int a = 0; a < 4; ++a) centre += 0.25 * mesh_.rest.col(mesh_.elements(a, worst));
  return fmt::format(
      "; at the last converged load the smallest J at a quadrature point is {:.4g}, in {} "
      "(centre {:.4g}, {:.4g}, {:.4g} m)",
      smallest, domain().TetName(worst), centre.x(), centre.y(), centre.z());
}

StepStatus MixedSolid::DoStep(double t, double dt) {
  failure_detail_.clear();
  step_time_ = t;
  step_dt_ = dt;
  failed_cavity_ = -1;
  if (params_.scheme == ImplicitSchemeKind::kNewmark && step_count() == 0) {
    // The first step's constraints and loads (its velocity targets are set again after Begin).
    static_cast<void>(GatherLoads());
    if (!InitialAcceleration()) {
      failure_detail_ = "Newmark's initial acceleration: " + failure_detail_;
      return StepStatus::Failed("Newmark's initial acceleration could not be solved");
    }
  }
  if (dynamic()) state_.scheme.Begin(dt);  // before GatherLoads: prescribed velocities need it
  if (const Index v = GatherLoads(); v >= 0) {
    failure_detail_ = fmt::format(
        "boundary vertex {} has a prescribed velocity; a quasi-static MixedSolid takes prescribed "
        "displacements only (a dynamic \"integrator\" takes velocities too)",
        v);
    return StepStatus::Failed("a prescribed velocity on a quasi-static MixedSolid", v);
  }
  // Prescribed displacements ramp from where the constrained dofs are now.
  for (int dof : constrained_dofs_) target_prev_[dof] = state_.z[dof];
  z_begin_ = state_.z;
  cavity_pressure_begin_ = state_.cavity_pressure;
  const StepStatus status = Advance(0, 1, 0);
  if (!status.ok()) {
    state_.z = z_begin_;
    state_.cavity_pressure = cavity_pressure_begin_;
    UpdatePositions();
    return status;
  }
  if (dynamic()) {
    const Index nu = 3 * mesh_.num_nodes();
    state_.scheme.Commit(state_.z.head(nu) - state_.scheme.x());
  }
  state_.force_prev = force_new_;
  state_.active_prev = state_.active_new;
  state_.pressure_prev = pressure_new_;
  state_.traction_prev = traction_new_;
  state_.have_prev = true;
  UpdatePositions();
  return StepStatus::Ok();
}

void MixedSolid::UpdatePositions() {
  const Index nv = mesh_.num_vertices;
  vertex_positions_ = domain().nodes + Eigen::Map<const Points>(state_.z.data(), 3, nv);
}

}  // namespace gipsi
