// MixedSolid's "schur_gmres" linear solver (saddle_point_solver.h): the Schur complement's
// approximation Ŝ and the displacement block's augmentation, both from the last tangent.

#include <algorithm>
#include <vector>

#include "gipsi/models/fem/mixed_solid.h"

namespace gipsi {

std::unique_ptr<LinearSolver> MixedSolid::MakeSchurSolver() {
  const Index ne = mesh_.num_elements();
  const Index nv = mesh_.num_vertices;
  const Index nu = 3 * mesh_.num_nodes();
  const TetQuadrature& rule = TetRuleDegree2();
  // Ŝ ≈ C + B K⁻¹ Bᵀ: each element's pressure mass ∫ L_a L_b dV over its shear modulus (plus
  // 1/κ, the C block's), in the scaled pressure's units (s² ×); the moduli follow the tangent
  // (UpdateSchur), so a stiffening law keeps GMRES's iteration count down.
  const double e0 = law_->small_strain_youngs_modulus();
  rest_shear_ = e0 / (2 * (1 + law_->small_strain_poisson_ratio()));
  element_shear_ = VecX::Constant(ne, rest_shear_);
  element_pressure_mass_.assign(static_cast<std::size_t>(ne) * 16, 0.0);
  std::vector<Eigen::Triplet<double, int>> entries;
  for (Index e2 = 0; e2 < ne; ++e2)
    for (int q = 0; q < kQuad; ++q) {
      const Eigen::Vector4d& l = rule.points[static_cast<std::size_t>(q)];
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) {
          element_pressure_mass_[static_cast<std::size_t>(e2 * 16 + 4 * b + a)] +=
              weight_[e2 * kQuad + q] * l[a] * l[b];
          entries.emplace_back(mesh_.elements(a, e2), mesh_.elements(b, e2), 0.0);
        }
    }
  schur_.resize(nv, nv);
  schur_.setFromTriplets(entries.begin(), entries.end());
  schur_.makeCompressed();
  schur_index_.resize(static_cast<std::size_t>(ne) * 16);
  for (Index e2 = 0; e2 < ne; ++e2)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const int col = mesh_.elements(b, e2), row = mesh_.elements(a, e2);
        const int* begin = schur_.innerIndexPtr() + schur_.outerIndexPtr()[col];
        const int* end = schur_.innerIndexPtr() + schur_.outerIndexPtr()[col + 1];
        schur_index_[static_cast<std::size_t>(e2 * 16 + 4 * b + a)] =
            static_cast<int>(std::lower_bound(begin, end, row) - schur_.innerIndexPtr());
      }
  FillSchur();
  augmentation_.assign(static_cast<std::size_t>(jac_.nonZeros()), 0.0);
  auto saddle = std::make_unique<SaddlePointSolver>(nu, schur_, params_.linear_solver);
  saddle_ = saddle.get();
  return saddle;
}

void MixedSolid::FillSchur() {
  const double inv_kappa = params_.incompressible ? 0.0 : 1.0 / kappa_;
  const double s2 = pressure_scale_ * pressure_scale_;
  double* values = schur_.valuePtr();
  std::fill(values, values + schur_.nonZeros(), 0.0);
  for (Index e = 0; e < mesh_.num_elements(); ++e) {
    // A modulus that the pressure's geometric term drives down (or below zero) is kept at a
    // hundredth of the law's small-strain one: Ŝ stays positive definite.
    const double mu = std::max(element_shear_[e], 0.01 * rest_shear_);
    const double c = s2 * (2 / mu + inv_kappa);  // 1/μ + 1/γ with γ = μ
    for (int k = 0; k < 16; ++k)
      values[schur_index_[static_cast<std::size_t>(e * 16 + k)]] +=
          c * element_pressure_mass_[static_cast<std::size_t>(e * 16 + k)];
  }
}

void MixedSolid::UpdatePreconditioner() {
  FillSchur();
  saddle_->UpdateSchur(schur_);
  saddle_->SetPrimaryAugmentation(augmentation_.data());
}

}  // namespace gipsi
