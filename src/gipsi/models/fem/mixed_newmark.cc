// MixedSolid's Newmark start: the initial accelerations, and the pressure that goes with them.

#include "gipsi/models/fem/mixed_solid.h"
#include "gipsi/numerics/sparse/linear_solver.h"

namespace gipsi {

bool MixedSolid::InitialAcceleration() {
  // The residual is affine in the pressure unknowns p̃: r(u, p̃) = r(u, 0) + J_·p p̃. So at the
  // current u (and velocity v₀), the equations of motion M a₀ + r_u(u, p̃₀) + α M v₀ = 0 and
  //  - incompressible: the constraint's second time derivative B a₀ = 0 (at rest; the term in
  //    v₀² is left out), a saddle point with M in place of K;
  //  - compressible: the pressure rows r_p(u, p̃₀) = 0, i.e. p₀ = κ ln J in the weak sense,
  // form one linear system on the Jacobian's pattern. Held dofs get a₀ = 0.
  const Index nu = 3 * mesh_.num_nodes();
  VecX z = state_.z;
  z.tail(z.size() - nu).setZero();
  SparseMatrix jac = jac_;
  VecX r = VecX::Zero(z.size());
  if (!Assemble(z, 1.0, r, jac.valuePtr())) {
    failure_detail_ = "an element is outside its law's domain at the initial state";
    return false;
  }
  AssembleLoads(z, 1.0, r, nullptr);
  AddCavityLoads(z, r, nullptr, false);
  VecX rhs = -r;
  if (params_.rayleigh_mass > 0) {
    Points v = Eigen::Map<const Points>(state_.scheme.v().data(), 3, mesh_.num_nodes());
    const Points mv = ApplyMass(v);
    rhs.head(nu) -= params_.rayleigh_mass * Eigen::Map<const VecX>(mv.data(), nu);
  }
  if (params_.incompressible) rhs.tail(rhs.size() - nu).setZero();
  double* jv = jac.valuePtr();
  for (Index c = 0; c < jac.outerSize(); ++c)
    for (int k = jac.outerIndexPtr()[c]; k < jac.outerIndexPtr()[c + 1]; ++k) {
      const int row = jac.innerIndexPtr()[k];
      // K goes (M replaces it); B goes too when compressible (the pressure rows are then
      // r_p = 0 at the given u, not a constraint on a₀).
      if (c < nu && (row < nu || !params_.incompressible)) jv[k] = 0;
    }
  for (Index e = 0; e < mesh_.num_elements(); ++e) {
    const Eigen::Map<const Eigen::Matrix<double, 10, 10>> m(mass_.data() +
                                                            static_cast<std::size_t>(e) * 100);
    const int* idx = element_value_index_.data() + static_cast<std::size_t>(e) * kLocal * kLocal;
    for (int b = 0; b < 10; ++b)
      for (int a = 0; a < 10; ++a)
        for (int i = 0; i < 3; ++i) jv[idx[(3 * b + i) * kLocal + 3 * a + i]] += m(a, b);
  }
  ApplyConstraints(rhs, jv);
  auto solver = MakeLinearSolver({.type = "umfpack", .tolerance = 1e-10});
  solver->AnalyzePattern(jac);
  VecX solution = VecX::Zero(rhs.size());
  if (!solver->Factorize(jac) || !solver->Solve(rhs, solution).converged || !solution.allFinite()) {
    failure_detail_ = "the mass and pressure system could not be solved";
    return false;
  }
  VecX a0 = solution.head(nu);
  for (int dof : constrained_dofs_) a0[dof] = 0;
  state_.scheme.SetAcceleration(a0);
  return true;
}

}  // namespace gipsi
