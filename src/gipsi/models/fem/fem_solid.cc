#include "gipsi/models/fem/fem_solid.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <utility>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/geometry/quality.h"
#include "gipsi/models/fem/fem_geometry.h"
#include "gipsi/models/fem/surface_loads.h"
#include "gipsi/numerics/adaptive_parallel.h"

namespace gipsi {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

}  // namespace

FemSolid::FemSolid(std::string name, std::shared_ptr<const Mesh> domain, FemParams params)
    : SimObject(std::move(name)),
      params_(std::move(params)),
      dist_(params_.distribution.get()),
      assembly_(*domain) {
  if (!params_.material)
    throw InputError(fmt::format("object '{}': FemSolid needs a material", this->path()));
  if (!(params_.density > 0))
    throw InputError(fmt::format("object '{}': density must be positive", this->path()));
  law_ = params_.material.get();
  SetGeometry(domain, dist_ ? dist_->boundary() : MakeBoundary(*domain));
  const Index n = domain->num_nodes();
  const Index ne = assembly_.num_elements();

  state_.active_tension = VecX::Zero(ne);
  state_.nodal_active_tension = VecX::Zero(n);
  if (law_->needs_fibres())
    state_.axes.Write().assign(static_cast<std::size_t>(ne),
                               MaterialAxes(params_.fibre, params_.sheet));
  lumped_mass_ = assembly_.LumpedMass(params_.density);
  for (Index i = 0; i < n; ++i)
    if (!(lumped_mass_[i] > 0))
      throw InputError(
          fmt::format("object '{}': node {} belongs to no tetrahedron (remove unused "
                      "nodes from the mesh)",
                      this->path(), i));
  jac_ = assembly_.MakePattern();
  if (!params_.lumped_mass) {
    mass_ = jac_;
    VecX values;
    assembly_.AssembleConsistentMass(params_.density, values);
    std::copy(values.data(), values.data() + values.size(), mass_.valuePtr());
  }
  if (params_.rayleigh_stiffness > 0) damping_k_ = jac_;

  rest_ = Eigen::Map<const VecX>(domain->nodes.data(), 3 * n);
  x_ = rest_;
  state_.scheme = ImplicitScheme(params_.scheme, params_.newmark_beta, params_.newmark_gamma);
  state_.scheme.Reset(VecX::Zero(3 * n), VecX::Zero(3 * n), VecX::Zero(3 * n));
  saved_scheme_ = begin_scheme_ = state_.scheme;
  newton_ = std::make_unique<NewtonSolver>(
      params_.newton, dist_ ? dist_->MakeLinearSolver(params_.linear_solver, rest_)
                            : MakeLinearSolver(params_.linear_solver));
  newton_->SetReduction(dist_);
  // Rigid-body modes of the rest shape: what an AMG preconditioner coarsens (others ignore it).
  newton_->linear_solver().SetNearNullSpace(RigidBodyModes(rest_));
  newton_->Prepare(jac_);
  positions_ = domain->nodes;
  state_.external_force.Write() = Points::Zero(3, n);

  const BoundarySurface& bnd = boundary();
  const Index nf = bnd.num_triangles();
  state_.f_nodal_prev = f_nodal_new_ = VecX::Zero(3 * n);
  state_.pressure_prev = pressure_new_ = VecX::Zero(nf);
  state_.traction_prev = traction_new_ = Points::Zero(3, nf);
  constraint_.assign(static_cast<std::size_t>(3 * n), 0);
  target_ = x_begin_ = VecX::Zero(3 * n);
  face_local_.resize(static_cast<std::size_t>(nf));
  for (Index f = 0; f < nf; ++f) {
    const int tet = bnd.face_to_tet[static_cast<std::size_t>(f)];
    for (int v = 0; v < 3; ++v) {
      const int node = bnd.vertex_to_node[static_cast<std::size_t>(bnd.triangles(v, f))];
      int local = -1;
      for (int a = 0; a < 4; ++a)
        if (assembly_.tets()(a, tet) == node) local = a;
      GIPSI_CHECK(local >= 0);
      face_local_[static_cast<std::size_t>(f)][static_cast<std::size_t>(v)] = local;
    }
  }
  f_int_ = f_ext_ = work_ = work2_ = d_ = VecX::Zero(3 * n);
  invalid_.assign(static_cast<std::size_t>(ne), 0);
  element_force_sum_ = VecX::Zero(ne);

  using L = FieldLocation;
  using A = FieldAccess;
  mech_ = DeclareMechanicalFields();
  f_fibre_ = DeclareField({"fibre", L::kElement, 3, "1", A::kReadWrite,
                           "fibre direction in the reference configuration (unit)"});
  f_active_ = DeclareField({"active_tension", L::kElement, 1, "Pa", A::kReadWrite,
                            "active tension along the fibre (2nd Piola-Kirchhoff Ta f x f)"});
  f_nodal_active_ = DeclareField({"nodal_active_tension", L::kNode, 1, "Pa", A::kReadWrite,
                                  "active tension per node (elements take the mean of theirs)"});
  f_von_mises_ = DeclareField(
      {"von_mises_stress", L::kElement, 1, "Pa", A::kRead, "von Mises equivalent Cauchy stress"});
  f_jacobian_ = DeclareField(
      {"volume_ratio", L::kElement, 1, "1", A::kRead, "det F (< 0 for an inverted element)"});
  f_kinetic_ = DeclareField({"kinetic_energy", L::kGlobal, 1, "J", A::kRead, "1/2 v' M v"});
  f_strain_energy_ =
      DeclareField({"strain_energy", L::kGlobal, 1, "J", A::kRead, "stored elastic energy"});
  f_newton_ = DeclareField(
      {"newton_iterations", L::kGlobal, 1, "1", A::kRead, "Newton iterations of the last step"});
  f_inverted_ = DeclareField(
      {"inverted_elements", L::kGlobal, 1, "1", A::kRead, "number of elements with det F <= 0"});
  f_volume_ = DeclareField({"volume", L::kGlobal, 1, "m^3", A::kRead,
                            "current volume (the sum of the tets' signed volumes)"});
  MakeCavities(*domain, bnd);
  state_.cavities.resize(cavities_.size());
  BindState(state_);
}

MaterialPoint FemSolid::PointOf(Index e) const {
  MaterialPoint mp;
  if (!state_.axes.get().empty()) mp.axes = state_.axes.get()[static_cast<std::size_t>(e)];
  if (state_.active_from_nodes) {
    double sum = 0;
    for (int a = 0; a < 4; ++a) sum += state_.nodal_active_tension[assembly_.tets()(a, e)];
    mp.active_tension = 0.25 * sum;
  } else {
    mp.active_tension = state_.active_tension[e];
  }
  return mp;
}

bool FemSolid::AssembleElements(const double* u, VecX& f, double* k_values) const {
  f.setZero(3 * num_nodes());
  if (k_values) {
    const Index nnz = jac_.nonZeros();
    ForRange(Index{0}, nnz, nnz >= 65536 && tangent_team_.prefers_parallel(),
             [=](Index j) { k_values[j] = 0.0; });
  }
  std::atomic<bool> any_invalid{false};
  double* fp = f.data();
  // Element e's force (and, with k_values, stiffness) from its stress P and stiffness K,
  // scattered into f and the tangent.
  const auto scatter = [&](Index e, bool ok, const Mat3& P, const auto& K) {
    invalid_[static_cast<std::size_t>(e)] = ok ? 0 : 1;
    element_force_sum_[e] = 0;
    if (!ok) {
      any_invalid.store(true, std::memory_order_relaxed);
      return;
    }
    const Eigen::Matrix<double, 3, 4> fe = assembly_.volume(e) * P * assembly_.gradients(e);
    element_force_sum_[e] = fe.cwiseAbs().sum();
    for (int a = 0; a < 4; ++a) {
      double* fa = fp + 3 * assembly_.tets()(a, e);
      fa[0] += fe(0, a);
      fa[1] += fe(1, a);
      fa[2] += fe(2, a);
    }
    if (!k_values) return;
    for (int b = 0; b < 4; ++b)
      for (int a = 0; a < 4; ++a)
        for (int k = 0; k < 3; ++k) {
          double* col = k_values + assembly_.ValueIndex(e, a, b, 0, k);
          col[0] += K(3 * a, 3 * b + k);
          col[1] += K(3 * a + 1, 3 * b + k);
          col[2] += K(3 * a + 2, 3 * b + k);
        }
  };
  if (!k_values) {
    assembly_.ForEachElementColoured(
        [&](Index e) {
          Mat3 P;
          const bool ok = law_->Stress(assembly_.DeformationGradient(e, u), PointOf(e), P);
          scatter(e, ok, P, [](int, int) { return 0.0; });  // no tangent
        },
        residual_team_);
  } else if (!law_->has_batch_kernel()) {
    assembly_.ForEachElementColoured(
        [&](Index e) {
          Mat3 P;
          Mat12 K;
          const bool ok =
              law_->ElementStressAndStiffness(assembly_.DeformationGradient(e, u), PointOf(e),
                                              assembly_.gradients(e), assembly_.volume(e), P, K);
          scatter(e, ok, P, K);
        },
        tangent_team_);
  } else {
    // Tangents in batches of ElementBatch::kLanes consecutive elements (the corotational law
    // evaluates a batch in vector lanes), scattered in element order: every entry receives its
    // element contributions in the same order as element by element.
    assembly_.ForEachChunkColoured(
        [&](Index first, Index last) {
          ElementBatch batch;
          for (Index begin = first; begin < last; begin += ElementBatch::kLanes) {
            batch.count = static_cast<int>(std::min<Index>(ElementBatch::kLanes, last - begin));
            for (int l = 0; l < batch.count; ++l) {
              const Index e = begin + l;
              batch.SetInput(l, assembly_.DeformationGradient(e, u), assembly_.gradients(e),
                             assembly_.volume(e), PointOf(e));
            }
            law_->ElementStressAndStiffnessBatch(batch);
            for (int l = 0; l < batch.count; ++l) {
              // K(r, c) of lane l, read in place.
              const auto K = [&batch, l](int r, int c) { return batch.K[r + 12 * c][l]; };
              scatter(begin + l, batch.ok[l], batch.OutputP(l), K);
            }
          }
        },
        tangent_team_);
  }
  // Assembling contributions of magnitude |f| into a residual loses ~ε|f| each, and forces
  // evaluated at a displacement u carry ~ε ‖K‖ ‖u‖: 100 ε times their sum bounds what any
  // iterate's residual can be told apart from zero (still ~1e-14 of the element forces).
  bool invalid = any_invalid.load();
  if (!dist_) {
    residual_floor_ = 100 * std::numeric_limits<double>::epsilon() *
                      (element_force_sum_.sum() +
                       state_.jacobian_norm * Eigen::Map<const VecX>(u, f.size()).norm());
  } else {
    // The same floor and verdict on every process: sums over the ranks (u over owned nodes).
    std::array<double, 3> sums{element_force_sum_.sum(),
                               Eigen::Map<const VecX>(u, dist_->owned()).squaredNorm(),
                               invalid ? 1.0 : 0.0};
    dist_->Reduce(sums, false);
    residual_floor_ = 100 * std::numeric_limits<double>::epsilon() *
                      (sums[0] + state_.jacobian_norm * std::sqrt(sums[1]));
    invalid = sums[2] > 0;
  }
  if (invalid) {
    first_invalid_ = -1;
    for (Index e = 0; e < num_elements(); ++e)
      if (invalid_[static_cast<std::size_t>(e)]) {
        first_invalid_ = e;
        break;
      }
    invalid_id_ = first_invalid_ >= 0 ? domain().TetId(first_invalid_) : -1;
    if (dist_) {  // the smallest identifier over the processes names the element
      double negated = first_invalid_ >= 0 ? -static_cast<double>(dist_->WholeTetId(first_invalid_))
                                           : -std::numeric_limits<double>::max();
      dist_->Reduce({&negated, 1}, true);
      invalid_id_ = static_cast<std::int64_t>(-negated);
    }
    return false;
  }
  return true;
}

bool FemSolid::CalcInternalForces(const VecX& x, VecX& f) const {
  GIPSI_CHECK(x.size() == 3 * num_nodes());
  work_ = x - rest_;
  return AssembleElements(work_.data(), f, nullptr);
}

bool FemSolid::CalcStiffness(const VecX& x, SparseMatrix& K) const {
  GIPSI_CHECK(x.size() == 3 * num_nodes());
  if (K.nonZeros() != jac_.nonZeros()) K = assembly_.MakePattern();
  work_ = x - rest_;
  return AssembleElements(work_.data(), f_int_, K.valuePtr());
}

void FemSolid::AssembleExternal(const double* u, double s) const {
  f_ext_ = state_.f_nodal_prev + s * (f_nodal_new_ - state_.f_nodal_prev);
  const BoundarySurface& bnd = boundary();
  for (Index f = 0; f < bnd.num_triangles(); ++f) {
    const double p = state_.pressure_prev[f] + s * (pressure_new_[f] - state_.pressure_prev[f]);
    const Vec3 t =
        state_.traction_prev.col(f) + s * (traction_new_.col(f) - state_.traction_prev.col(f));
    if (p == 0 && t.squaredNorm() == 0) continue;
    int node[3];
    for (int v = 0; v < 3; ++v)
      node[v] = bnd.vertex_to_node[static_cast<std::size_t>(bnd.triangles(v, f))];
    Vec3 fl[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    Vec3 xf[3];
    for (int v = 0; v < 3; ++v)
      xf[v] = rest_.segment<3>(3 * node[v]) + Eigen::Map<const Vec3>(u + 3 * node[v]);
    FaceLoads(xf[0], xf[1], xf[2], p, t, fl[0], fl[1], fl[2]);
    for (int v = 0; v < 3; ++v) f_ext_.segment<3>(3 * node[v]) += fl[v];
  }
}

void FemSolid::FinishResidual(const VecX& d, VecX& r) {
  // (Distributed: every term is a sum over the part's tets and owned nodes, made whole below.)
  r = f_int_ - f_ext_;
  if (params_.scheme != ImplicitSchemeKind::kStatic) {
    // Inertia M a and damping α M v + β K_n v.
    work_ = state_.scheme.c_a() * d + state_.scheme.a_hat();
    work2_ = state_.scheme.c_v() * d + state_.scheme.v_hat();
    if (params_.rayleigh_mass > 0) work_ += params_.rayleigh_mass * work2_;
    if (params_.lumped_mass) {
      for (Index i = 0; i < num_nodes(); ++i)
        r.segment<3>(3 * i) += lumped_mass_[i] * work_.segment<3>(3 * i);
    } else {
      // The products follow the residual loop's team (beside a busy neighbour, alone).
      VecX& ma = f_int_;  // f_int_ is consumed above; reuse as a buffer
      SymmetricSpMV(mass_, work_, ma, residual_team_.prefers_parallel());
      r += ma;
    }
    if (params_.rayleigh_stiffness > 0) {
      SymmetricSpMV(damping_k_, work2_, work_, residual_team_.prefers_parallel());
      r += params_.rayleigh_stiffness * work_;
    }
  }
  if (dist_) dist_->SumShared(r);
  for (int dof : constrained_dofs_) r[dof] = 0;
}

/// One load increment of a step as the nonlinear system r(d) = 0 that Newton solves, in the
/// increment d = x − x_n. Everything the residual depends on is an argument or the object's
/// state at the start of the increment: the load fraction `s` (the loads are interpolated
/// between the previous step's, s = 0, and this step's, s = 1) and the constraint targets.
/// What changes while Newton runs belongs to this solve only, and is here:
/// - the force scale of the convergence test: the applied nodal loads at s, raised at the first
///   residual Newton evaluates to the applied loads there, pressures included (a heart's only
///   loads are its cavity pressure and its own active tension);
/// - whether Rayleigh damping's K_n, the element tangent at the increment's first iterate, has
///   been taken (from the first tangent Newton assembles, so it costs no extra assembly).
class FemSolid::Increment final : public NonlinearSystem {
 public:
  Increment(FemSolid& solid, double s, double nodal_load_scale)
      : solid_(solid),
        s_(s),
        force_scale_(nodal_load_scale),
        damping_pending_(solid.params_.rayleigh_stiffness > 0) {}

  bool CalcResidual(const VecX& d, VecX& r) override {
    if (solid_.bordered_ == 0) {
      const bool ok = solid_.IncrementResidual(s_, d, r);
      if (ok) TakeLoadScale();
      return ok;
    }
    const bool ok = solid_.IncrementResidual(s_, solid_.TakeIterate(d), solid_.bordered_r_);
    if (ok) {
      solid_.GiveResidual(r);
      TakeLoadScale();
    }
    return ok;
  }
  bool CalcResidualAndJacobian(const VecX& d, VecX& r, SparseMatrix& J) override {
    bool ok = false;
    if (solid_.bordered_ == 0) {
      ok = solid_.IncrementResidualAndJacobian(s_, d, r, J, damping_pending_);
    } else {
      ok = solid_.IncrementResidualAndJacobian(s_, solid_.TakeIterate(d), solid_.bordered_r_, J,
                                               damping_pending_);
      if (ok) solid_.GiveResidual(r);
    }
    if (ok) {
      TakeLoadScale();
      damping_pending_ = false;
    }
    return ok;
  }
  [[nodiscard]] double force_scale() const override { return force_scale_; }
  [[nodiscard]] double residual_floor() const override { return solid_.residual_floor_; }
  [[nodiscard]] int num_low_rank_terms() const override { return solid_.num_low_rank_terms(); }
  void LowRankTerm(int k, const VecX*& b, double& w) const override { solid_.LowRankTerm(k, b, w); }
  [[nodiscard]] int num_bordered() const override { return solid_.bordered_; }

 private:
  void TakeLoadScale() {
    if (!scale_pending_) return;
    scale_pending_ = false;
    force_scale_ = std::max(force_scale_, solid_.AppliedLoadNorm());
  }

  FemSolid& solid_;
  const double s_;
  double force_scale_;
  bool damping_pending_;
  bool scale_pending_ = true;
};

const VecX& FemSolid::TakeIterate(const VecX& x) {
  const Index n = bordered_d_.size();
  bordered_d_ = x.head(n);
  Index k = n;
  for (std::size_t c = 0; c < cavities_.size(); ++c)
    if (cavities_[c].law != nullptr) state_.cavities[c].pressure = x[k++];
  return bordered_d_;
}

void FemSolid::GiveIterate(VecX& x) const {
  const Index n = d_.size();
  x.head(n) = d_;
  Index k = n;
  for (std::size_t c = 0; c < cavities_.size(); ++c)
    if (cavities_[c].law != nullptr) x[k++] = state_.cavities[c].pressure;
}

void FemSolid::GiveResidual(VecX& r) const {
  const Index n = bordered_r_.size();
  r.head(n) = bordered_r_;
  Index k = n;
  for (const Cavity& cavity : cavities_)
    if (cavity.law != nullptr) r[k++] = cavity.volume_residual;
}

bool FemSolid::IncrementResidual(double s, const VecX& d, VecX& r) {
  const auto start = Clock::now();
  work_ = state_.scheme.x() + d;
  bool ok = AssembleElements(work_.data(), f_int_, nullptr);
  if (ok) {
    AssembleExternal(work_.data(), s);
    ok = AddCoupledCavityLoads(work_.data());
    if (ok) FinishResidual(d, r);
  }
  profile_.assembly_seconds += Seconds(start);
  return ok;
}

double FemSolid::AppliedLoadNorm() const {
  if (dist_) return WholeNorm(f_ext_, true);
  double sum = f_ext_.squaredNorm();
  for (int dof : constrained_dofs_) sum -= f_ext_[dof] * f_ext_[dof];
  return std::sqrt(std::max(sum, 0.0));
}

double FemSolid::WholeNorm(const VecX& v, bool free_only) const {
  if (!dist_) return v.norm();
  whole_work_ = v;
  dist_->SumShared(whole_work_);
  if (free_only)
    for (int dof : constrained_dofs_) whole_work_[dof] = 0;
  double sum = whole_work_.head(dist_->owned()).squaredNorm();
  dist_->Reduce({&sum, 1}, false);
  return std::sqrt(sum);
}

bool FemSolid::IncrementResidualAndJacobian(double s, const VecX& d, VecX& r, SparseMatrix& J,
                                            bool damping_tangent) {
  const auto start = Clock::now();
  work_ = state_.scheme.x() + d;
  if (!AssembleElements(work_.data(), f_int_, J.valuePtr())) {
    profile_.assembly_seconds += Seconds(start);
    return false;
  }
  AssembleExternal(work_.data(), s);
  if (!AddCoupledCavityLoads(work_.data())) {
    profile_.assembly_seconds += Seconds(start);
    return false;
  }
  double* jv = J.valuePtr();
  const Index nnz = J.nonZeros();
  if (damping_tangent) std::copy(jv, jv + nnz, damping_k_.valuePtr());
  // Symmetric part of the follower-load tangent: J −= sym(∂f_ext/∂x).
  const BoundarySurface& bnd = boundary();
  for (Index f = 0; f < bnd.num_triangles(); ++f) {
    const double p = state_.pressure_prev[f] + s * (pressure_new_[f] - state_.pressure_prev[f]);
    const Vec3 t =
        state_.traction_prev.col(f) + s * (traction_new_.col(f) - state_.traction_prev.col(f));
    if (p == 0 && t.squaredNorm() == 0) continue;
    AddFaceLoadTangent(f, work_.data(), p, t, jv);
  }
  AddCoupledCavityTangent(work_.data(), jv);
  // Inertia and damping: J += (c_a + c_v α) M + c_v β K_n, added in the same parallel pass
  // over the values as the constraints below (one sweep of the matrix instead of three).
  const bool dynamic = params_.scheme != ImplicitSchemeKind::kStatic;
  const double cm =
      dynamic ? state_.scheme.c_a() + state_.scheme.c_v() * params_.rayleigh_mass : 0.0;
  const double ck = dynamic ? state_.scheme.c_v() * params_.rayleigh_stiffness : 0.0;
  if (dynamic && params_.lumped_mass) {
    const auto& diag = assembly_.diagonal_index();
    for (std::size_t i = 0; i < diag.size(); ++i)
      jv[diag[i]] += cm * lumped_mass_[static_cast<Index>(i / 3)];
  }
  const double* mv = dynamic && !params_.lumped_mass ? mass_.valuePtr() : nullptr;
  const double* kv = ck > 0 ? damping_k_.valuePtr() : nullptr;
  auto with_inertia = [=](Index j) {
    double v = jv[j];
    if (mv) v += cm * mv[j];
    if (kv) v += ck * kv[j];
    return v;
  };
  // Constrained dofs: rows and columns of the identity times the mean diagonal (keeps J
  // symmetric and well scaled; their increment is 0). Also the largest absolute row sum, which
  // bounds the round-off of any solve with J: a backward-stable solve leaves a residual of
  // ~ε ‖J‖ ‖Δ‖, which no further Newton step can remove.
  const int* outer = J.outerIndexPtr();
  const int* inner = J.innerIndexPtr();
  const int ncols = static_cast<int>(J.cols());
  double diag_sum = 0;
  for (int index : assembly_.diagonal_index()) diag_sum += std::abs(with_inertia(index));
  const double unit = diag_sum > 0 ? diag_sum / static_cast<double>(ncols) : 1.0;
  const std::uint8_t* constraint = constraint_.data();
  // Distributed, only the owner puts a shared dof's unit on the diagonal (the processes'
  // matrices are summed).
  const int owned = dist_ ? static_cast<int>(dist_->owned()) : ncols;
  double max_row_sum = 0;
  auto finish_column = [&](int c) {  // returns the column's absolute sum
    const bool fixed_col = constraint[c] != 0;
    double row_sum = 0;
    for (int j = outer[c]; j < outer[c + 1]; ++j) {
      double v = with_inertia(j);
      if (fixed_col || constraint[inner[j]] != 0) v = inner[j] == c && c < owned ? unit : 0.0;
      jv[j] = v;
      row_sum += std::abs(v);
    }
    return row_sum;
  };
  // (A maximum is exact in any order: the team's choice cannot change the bits. A serial
  // choice opens no region; see ForRange.)
  if (nnz >= 65536 && tangent_team_.prefers_parallel()) {
#pragma omp parallel for schedule(static) reduction(max : max_row_sum)
    for (int c = 0; c < ncols; ++c) max_row_sum = std::max(max_row_sum, finish_column(c));
  } else {
    for (int c = 0; c < ncols; ++c) max_row_sum = std::max(max_row_sum, finish_column(c));
  }
  Reduce({&max_row_sum, 1}, true);
  state_.jacobian_norm = max_row_sum;
  FinishResidual(d, r);
  profile_.assembly_seconds += Seconds(start);
  return true;
}

void FemSolid::AddFaceLoadTangent(Index f, const double* u, double p, const Vec3& t,
                                  double* jv) const {
  const BoundarySurface& bnd = boundary();
  int node[3];
  for (int v = 0; v < 3; ++v)
    node[v] = bnd.vertex_to_node[static_cast<std::size_t>(bnd.triangles(v, f))];
  Vec3 xf[3];
  for (int v = 0; v < 3; ++v)
    xf[v] = rest_.segment<3>(3 * node[v]) + Eigen::Map<const Vec3>(u + 3 * node[v]);
  const Mat99 jf = FaceLoadJacobian(xf[0], xf[1], xf[2], p, t);
  const Mat99 sym = 0.5 * (jf + jf.transpose());
  const int tet = bnd.face_to_tet[static_cast<std::size_t>(f)];
  const auto& local = face_local_[static_cast<std::size_t>(f)];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      for (int k = 0; k < 3; ++k) {
        double* col = jv + assembly_.ValueIndex(tet, local[static_cast<std::size_t>(a)],
                                                local[static_cast<std::size_t>(b)], 0, k);
        for (int i = 0; i < 3; ++i) col[i] -= sym(3 * a + i, 3 * b + k);
      }
}

void FemSolid::GatherTargets() {
  const Index n = num_nodes();
  const BoundarySurface& bnd = boundary();
  const BoundaryConditions& bcs = boundary_conditions();
  // Nodal forces count once: distributed, on the node's owner (the lumped mass is the part's
  // share, so its weight adds up over the processes).
  const Index owned = dist_ ? dist_->num_owned_nodes() : n;
  for (Index i = 0; i < n; ++i)
    f_nodal_new_.segment<3>(3 * i) =
        lumped_mass_[i] * params_.gravity +
        (i < owned ? Vec3(state_.external_force.get().col(i)) : Vec3::Zero());
  for (Index j = 0; j < bnd.num_vertices(); ++j) {
    const int node = bnd.vertex_to_node[static_cast<std::size_t>(j)];
    if (node < owned) f_nodal_new_.segment<3>(3 * node) += bcs.force(j);
  }
  for (Index f = 0; f < bnd.num_triangles(); ++f) {
    pressure_new_[f] = bcs.pressure(f);
    traction_new_.col(f) = bcs.traction(f);
  }
  for (std::size_t c = 0; c < cavities_.size(); ++c)
    if (cavities_[c].law == nullptr)
      for (int f : cavities_[c].faces) pressure_new_[f] += state_.cavities[c].pressure;
  constrained_dofs_.clear();
  std::fill(constraint_.begin(), constraint_.end(), 0);
  for (Index j = 0; j < bnd.num_vertices(); ++j) {
    const Index node = bnd.vertex_to_node[static_cast<std::size_t>(j)];
    for (int a = 0; a < 3; ++a) {
      const Index dof = 3 * node + a;
      switch (bcs.kind(j, a)) {
        case ConstraintKind::kFree:
          continue;
        case ConstraintKind::kDisplacement:
          constraint_[static_cast<std::size_t>(dof)] = 1;
          target_[dof] = bcs.value(j)[a];
          break;
        case ConstraintKind::kVelocity:
          constraint_[static_cast<std::size_t>(dof)] = 2;
          target_[dof] = bcs.value(j)[a];
          break;
      }
      constrained_dofs_.push_back(static_cast<int>(dof));
    }
  }
  if (!state_.have_prev_loads) {
    // Quasi-static analysis starts unloaded and ramps; dynamics starts with its loads applied.
    if (params_.scheme == ImplicitSchemeKind::kStatic) {
      state_.f_nodal_prev.setZero();
      state_.pressure_prev.setZero();
      state_.traction_prev.setZero();
    } else {
      state_.f_nodal_prev = f_nodal_new_;
      state_.pressure_prev = pressure_new_;
      state_.traction_prev = traction_new_;
    }
    state_.have_prev_loads = true;
  }
}

void FemSolid::InitialAcceleration() {
  // Newmark needs a_0 from M a_0 = f_ext − f_int − C v_0 (lumped: nodal division; consistent:
  // solved with a direct factorisation of M, once). Split over processes, the forces and the
  // masses are the part's partial sums at shared nodes: the right-hand side is summed (every
  // process then holds the whole one), the lumped masses too, and the consistent M is the
  // processes' partial matrices, which the distributed solver sums.
  if (!AssembleElements(state_.scheme.x().data(), f_int_, nullptr)) return;
  AssembleExternal(state_.scheme.x().data(), 0.0);
  VecX rhs = f_ext_ - f_int_;
  if (params_.rayleigh_mass > 0) {
    if (params_.lumped_mass) {
      for (Index i = 0; i < num_nodes(); ++i)
        rhs.segment<3>(3 * i) -=
            params_.rayleigh_mass * lumped_mass_[i] * state_.scheme.v().segment<3>(3 * i);
    } else {
      SymmetricSpMV(mass_, state_.scheme.v(), work_);
      rhs -= params_.rayleigh_mass * work_;
    }
  }
  if (dist_) dist_->SumShared(rhs);
  VecX a0 = VecX::Zero(rhs.size());
  if (params_.lumped_mass) {
    VecX mass(rhs.size());
    for (Index i = 0; i < num_nodes(); ++i) mass.segment<3>(3 * i).setConstant(lumped_mass_[i]);
    if (dist_) dist_->SumShared(mass);
    a0 = rhs.cwiseQuotient(mass);
  } else {
    const LinearSolverOptions direct{.type = "ldlt"};
    auto solver = dist_ ? dist_->MakeLinearSolver(direct, rest_) : MakeLinearSolver(direct);
    solver->AnalyzePattern(mass_);
    if (solver->Factorize(mass_)) solver->Solve(rhs, a0);
  }
  for (int dof : constrained_dofs_) a0[dof] = 0;
  state_.scheme.SetAcceleration(a0);
}

StepStatus FemSolid::Advance(double s0, double s1, double dt, int depth) {
  // A stop request is honoured before every load increment and bisection, and inside Newton.
  if (stop_token().stop_requested()) return StepStatus::Stopped();
  saved_scheme_ = state_.scheme;
  state_.scheme.Begin((s1 - s0) * dt);
  const bool predict = params_.predictor != FemParams::Predictor::kNone &&
                       params_.scheme != ImplicitSchemeKind::kStatic;
  auto solve = [&](bool predicted) {
    PredictIncrement(state_.scheme, predicted ? params_.predictor : StepPredictor::kNone,
                     (s1 - s0) * dt, d_);
    const VecX& xn = state_.scheme.x();
    for (int dof : constrained_dofs_) {
      if (constraint_[static_cast<std::size_t>(dof)] == 1)
        d_[dof] = x_begin_[dof] + s1 * (target_[dof] - x_begin_[dof]) - xn[dof];
      else
        d_[dof] = state_.scheme.IncrementForVelocity(dof, target_[dof]);
    }
    work2_ = state_.f_nodal_prev + s1 * (f_nodal_new_ - state_.f_nodal_prev);
    Increment increment(*this, s1, WholeNorm(work2_, false));
    if (bordered_ == 0) {
      state_.last_newton = newton_->Solve(increment, d_, jac_, stop_token());
    } else {
      // The iterate (d, p) starts from the step's first pressures (those of the last step).
      GiveIterate(newton_x_);
      state_.last_newton = newton_->Solve(increment, newton_x_, jac_, stop_token());
      d_ = TakeIterate(newton_x_);  // the last residual may have been a rejected trial's
    }
    load_scale_ = increment.force_scale();
    if (state_.last_newton.switched_to_indefinite)  // once per run: the switch is for good
      Log().warn(
          "{}: t = {:.6g} s, load increment to {:.4g} % of the step: the tangent is not "
          "positive definite (a large load increment, a follower pressure or a stiff "
          "bulk_modulus); the '{}' solver factorises it as LDLT from now on (docs/newton.md)",
          path(), time(), 100 * s1, newton_->linear_solver().name());
  };
  solve(predict);
  if (predict && state_.last_newton.inadmissible && state_.last_newton.iterations == 0) {
    RestoreCavityPressures();  // the predicted state was not admissible: start from x_n
    solve(false);
  }
  profile_.newton_iterations += state_.last_newton.iterations;
  profile_.linear_iterations += state_.last_newton.linear_iterations;
  profile_.factorizations += state_.last_newton.refactorizations;
  if (state_.last_newton.converged && d_.allFinite()) {
    state_.scheme.Commit(d_);
    return StepStatus::Ok();
  }
  state_.scheme = saved_scheme_;
  RestoreCavityPressures();
  if (state_.last_newton.interrupted) return StepStatus::Stopped();
  // Newton extends its budget while it converges (newton.h), so what arrives here is not
  // converging: a smaller increment is the remedy.
  if (depth < params_.max_bisections) {
    const double mid = 0.5 * (s0 + s1);
    StepStatus status = Advance(s0, mid, dt, depth + 1);
    if (!status.ok()) return status;
    return Advance(mid, s1, dt, depth + 1);
  }
  failure_detail_ = Describe(state_.last_newton, params_.newton, newton_->linear_solver().name());
  if (failed_cavity_ >= 0)
    failure_detail_ += fmt::format(
        "; the blood coupled to cavity '{}' could not give its volume at the wall's pressure, or "
        "its volume does not fall as the pressure rises (is the blood object stepped right after "
        "this one?)",
        params_.cavities[static_cast<std::size_t>(failed_cavity_)].name);
  if (state_.last_newton.inadmissible && invalid_id_ >= 0)
    failure_detail_ += fmt::format("; tet {} ({}) is outside its law's domain (det F <= 0?)",
                                   invalid_id_, domain().TetIdKind());
  if (state_.last_newton.inadmissible && failed_cavity_ >= 0)
    return StepStatus::Failed("the blood coupled to a cavity could not answer; cavity",
                              failed_cavity_);
  if (state_.last_newton.inadmissible)
    return StepStatus::Failed("no admissible state: an element inverted; tet", invalid_id_);
  if (state_.last_newton.linear_failure)
    return StepStatus::Failed(
        state_.last_newton.linear_failure_kind == LinearFailure::kNotConverged
            ? "the linear solve of the Newton step failed"
            : "the tangent matrix could not be factorised (indefinite or singular)");
  return StepStatus::Failed("Newton did not converge; final residual", -1,
                            state_.last_newton.final_residual);
}

StepStatus FemSolid::DoStep(double t, double dt) {
  if (ode_integrator_) return StepOde(t, dt);
  step_time_ = t;
  step_dt_ = dt;
  failed_cavity_ = -1;
  for (std::size_t c = 0; c < cavities_.size(); ++c)
    cavities_[c].pressure_begin = state_.cavities[c].pressure;
  GatherTargets();
  if (params_.scheme == ImplicitSchemeKind::kNewmark && step_count() == 0) InitialAcceleration();
  x_begin_ = state_.scheme.x();
  begin_scheme_ = state_.scheme;  // for a stop inside the step (allocation-free: same sizes)
  failure_detail_.clear();
  const auto start = Clock::now();
  const double solve_before = profile_.assembly_seconds;
  StepStatus status = StepStatus::Ok();
  const int pieces = std::max(1, params_.load_steps);
  for (int k = 0; k < pieces && status.ok(); ++k)
    status = Advance(double(k) / pieces, double(k + 1) / pieces, dt, 0);
  profile_.solve_seconds += Seconds(start) - (profile_.assembly_seconds - solve_before);
  ++profile_.steps;
  if (status.code == StepStatus::Code::kStopped) {
    // Abandon the whole step, committed load increments and bisections included: the object
    // is back at the start of the step, consistent with its clock.
    state_.scheme = begin_scheme_;
    RestoreCavityPressures();
  }
  UpdatePositions();
  if (!status.ok()) return status;
  state_.f_nodal_prev = f_nodal_new_;
  state_.pressure_prev = pressure_new_;
  state_.traction_prev = traction_new_;
  if (!state_.scheme.x().allFinite() || !state_.scheme.v().allFinite())
    return StepStatus::Diverged("non-finite position or velocity");
  return StepStatus::Ok();
}

std::vector<SimObject::ProfileEntry> FemSolid::ProfileBreakdown() const {
  return {{"assembly (residual, tangent)", profile_.assembly_seconds, "s"},
          {"linear solves", profile_.solve_seconds, "s"},
          {"Newton iterations", static_cast<double>(profile_.newton_iterations), ""},
          {"linear iterations", static_cast<double>(profile_.linear_iterations), ""},
          {"factorisations or preconditioner set-ups", static_cast<double>(profile_.factorizations),
           ""}};
}

void FemSolid::UpdatePositions() {
  x_ = rest_ + state_.scheme.x();
  positions_ = Eigen::Map<const Points>(x_.data(), 3, num_nodes());
}

double FemSolid::StrainEnergy() const {
  double energy = 0;
  for (Index e = 0; e < num_elements(); ++e)
    energy += assembly_.volume(e) *
              law_->Energy(assembly_.DeformationGradient(e, u().data()), PointOf(e));
  Reduce({&energy, 1});
  return energy;
}

double FemSolid::KineticEnergy() const {
  if (params_.lumped_mass) {
    double e = 0;
    for (Index i = 0; i < num_nodes(); ++i)
      e += 0.5 * lumped_mass_[i] * v().segment<3>(3 * i).squaredNorm();
    Reduce({&e, 1});
    return e;
  }
  SymmetricSpMV(mass_, v(), work_);
  double e = 0.5 * v().dot(work_);  // distributed: vᵀ (the part's M) v, summed
  Reduce({&e, 1});
  return e;
}

double FemSolid::GravityEnergy() const {
  double e = 0;
  for (Index i = 0; i < num_nodes(); ++i)
    e -= lumped_mass_[i] * params_.gravity.dot(u().segment<3>(3 * i));
  Reduce({&e, 1});
  return e;
}

Index FemSolid::CountInvertedElements() const {
  Index count = 0;
  for (Index e = 0; e < num_elements(); ++e)
    if (assembly_.DeformationGradient(e, u().data()).determinant() <= 0) ++count;
  if (dist_) {
    auto total = static_cast<double>(count);
    dist_->Reduce({&total, 1}, false);
    count = static_cast<Index>(total);
  }
  return count;
}

Mat3 FemSolid::CauchyStress(Index e) const {
  const Mat3 F = assembly_.DeformationGradient(e, u().data());
  Mat3 P;
  const double j = F.determinant();
  if (j <= 0 || !law_->Stress(F, PointOf(e), P)) return Mat3::Zero();
  return P * F.transpose() / j;
}

const double* FemSolid::DoFieldMemory(FieldId id) const {
  if (id == mech_.position) return positions_.data();
  if (id == mech_.velocity) return v().data();
  if (id == mech_.external_force) return state_.external_force.get().data();
  return nullptr;
}

void FemSolid::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  const Index n = num_nodes();
  const auto& v2n = boundary().vertex_to_node;
  if (ReadBoundaryKinematics(mech_, id, positions_, v().data(), out)) return;
  if (id == mech_.position) {
    out = positions_;
  } else if (id == mech_.velocity) {
    out = Eigen::Map<const Points>(v().data(), 3, n);
  } else if (id == mech_.displacement) {
    out = positions_ - domain().nodes;
  } else if (id == mech_.external_force) {
    out = state_.external_force.get();
  } else if (id == mech_.reaction_force) {
    // Reaction = M a + C v + f_int − f_ext on constrained axes, at the current state.
    out.setZero();
    if (!AssembleElements(u().data(), f_int_, nullptr)) return;
    AssembleExternal(u().data(), 1.0);  // after a step the previous loads equal the new ones
    AddCoupledCavityForces(f_ext_);
    work2_ = f_int_ - f_ext_;
    if (params_.scheme != ImplicitSchemeKind::kStatic) {
      if (params_.lumped_mass) {
        for (Index i = 0; i < n; ++i)
          work2_.segment<3>(3 * i) += lumped_mass_[i] * a().segment<3>(3 * i);
      } else {
        SymmetricSpMV(mass_, a(), work_);
        work2_ += work_;
      }
    }
    if (dist_) dist_->SumShared(work2_);
    const BoundaryConditions& bcs = boundary_conditions();
    for (std::size_t j = 0; j < v2n.size(); ++j) {
      const auto col = static_cast<Index>(j);
      for (int a = 0; a < 3; ++a)
        if (bcs.kind(col, a) != ConstraintKind::kFree) out(a, col) = work2_[3 * v2n[j] + a];
    }
  } else if (id == f_fibre_) {
    for (Index e = 0; e < num_elements(); ++e)
      out.col(e) = state_.axes.get().empty()
                       ? Vec3(MaterialAxes(params_.fibre, params_.sheet).col(0))
                       : Vec3(state_.axes.get()[static_cast<std::size_t>(e)].col(0));
  } else if (id == f_active_) {
    for (Index e = 0; e < num_elements(); ++e) out(0, e) = PointOf(e).active_tension;
  } else if (id == f_nodal_active_) {
    out = state_.nodal_active_tension.transpose();
  } else if (id == f_von_mises_) {
    for (Index e = 0; e < num_elements(); ++e) {
      const Mat3 s = CauchyStress(e);
      const Mat3 dev = s - s.trace() / 3.0 * Mat3::Identity();
      out(0, e) = std::sqrt(1.5 * dev.squaredNorm());
    }
  } else if (id == f_jacobian_) {
    for (Index e = 0; e < num_elements(); ++e)
      out(0, e) = assembly_.DeformationGradient(e, u().data()).determinant();
  } else if (id == f_kinetic_) {
    out(0, 0) = KineticEnergy();
  } else if (id == f_strain_energy_) {
    out(0, 0) = StrainEnergy();
  } else if (id == f_newton_) {
    out(0, 0) = state_.last_newton.iterations;
  } else if (id == f_inverted_) {
    out(0, 0) = static_cast<double>(CountInvertedElements());
  } else if (id == f_volume_) {
    double v = 0;
    const auto& tets = assembly_.tets();
    for (Index e = 0; e < tets.cols(); ++e)
      v += TetSignedVolume(positions_.col(tets(0, e)), positions_.col(tets(1, e)),
                           positions_.col(tets(2, e)), positions_.col(tets(3, e)));
    Reduce({&v, 1});
    out(0, 0) = v;
  } else {
    for (std::size_t i = 0; i < cavities_.size(); ++i) {
      if (id == cavities_[i].f_volume) out(0, 0) = CavityVolume(i);
      if (id == cavities_[i].f_pressure) out(0, 0) = state_.cavities[i].pressure;
    }
  }
}

void FemSolid::DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) {
  const Index n = num_nodes();
  if (id == mech_.position) {
    positions_ = in;
    state_.scheme.SetPositions(Eigen::Map<const VecX>(positions_.data(), 3 * n) - rest_);
    UpdatePositions();
  } else if (id == mech_.velocity) {
    state_.scheme.SetVelocity(Eigen::Map<const VecX>(in.data(), 3 * n));
  } else if (id == mech_.external_force) {
    state_.external_force.Write() = in;
  } else if (id == f_fibre_) {
    std::vector<Mat3>& all = state_.axes.Write();
    if (all.empty())
      all.assign(static_cast<std::size_t>(num_elements()),
                 MaterialAxes(params_.fibre, params_.sheet));
    for (Index e = 0; e < num_elements(); ++e) {
      Mat3& axes = all[static_cast<std::size_t>(e)];
      const Vec3 fibre = in.col(e);
      if (fibre.squaredNorm() > 0) axes = MaterialAxes(fibre, axes.col(1));
    }
  } else if (id == f_active_) {
    state_.active_tension = in.row(0).transpose();
    state_.active_from_nodes = false;
  } else if (id == f_nodal_active_) {
    state_.nodal_active_tension = in.row(0).transpose();
    state_.active_from_nodes = true;
  } else {
    for (std::size_t c = 0; c < cavities_.size(); ++c)
      if (id == cavities_[c].f_pressure && cavities_[c].law == nullptr)
        state_.cavities[c].pressure = in(0, 0);
  }
}

}  // namespace gipsi
