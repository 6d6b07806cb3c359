/// @file
/// Scalar P1 operators on tetrahedra.

#include "gipsi/numerics/p1_scalar.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "gipsi/base/error.h"

namespace gipsi {

Eigen::Matrix<double, 4, 3> P1Gradients(const Points& nodes, const Tets& tets, Index e,
                                        double* volume) {
  Mat3 edges;
  const Vec3 x0 = nodes.col(tets(0, e));
  for (int a = 0; a < 3; ++a) edges.col(a) = nodes.col(tets(a + 1, e)) - x0;
  const double det = edges.determinant();
  const double scale = edges.colwise().norm().maxCoeff();
  if (!(std::abs(det) > 1e-12 * scale * scale * scale) || !std::isfinite(det))
    throw InputError(fmt::format("tet {} of the domain mesh is degenerate (zero volume)", e));
  // Rows of edges⁻¹ are the gradients of the barycentric functions of nodes 1..3; node 0's is
  // their negative sum.
  const Mat3 inv = edges.inverse();
  Eigen::Matrix<double, 4, 3> grad;
  grad.bottomRows<3>() = inv;
  grad.row(0) = -inv.colwise().sum();
  if (volume != nullptr) *volume = std::abs(det) / 6.0;
  return grad;
}

P1ScalarOperators AssembleP1Scalar(const Points& nodes, const Tets& tets, double length_scale,
                                   const std::function<Mat3(Index)>& diffusivity,
                                   bool consistent_mass) {
  const Points scaled = length_scale * nodes;
  const Index num_tets = tets.cols();
  std::vector<Eigen::Triplet<double, int>> k_entries, m_entries;
  k_entries.reserve(static_cast<std::size_t>(16 * num_tets));
  if (consistent_mass) m_entries.reserve(static_cast<std::size_t>(16 * num_tets));
  P1ScalarOperators ops;
  ops.lumped_mass = VecX::Zero(nodes.cols());
  for (Index e = 0; e < num_tets; ++e) {
    double volume = 0;
    const Eigen::Matrix<double, 4, 3> grad = P1Gradients(scaled, tets, e, &volume);
    const Eigen::Matrix4d ke = volume * grad * diffusivity(e) * grad.transpose();
    for (int a = 0; a < 4; ++a) {
      const int ia = tets(a, e);
      ops.lumped_mass[ia] += volume / 4;
      for (int b = 0; b < 4; ++b) {
        const int ib = tets(b, e);
        k_entries.emplace_back(ia, ib, ke(a, b));
        if (consistent_mass) m_entries.emplace_back(ia, ib, volume * (a == b ? 2.0 : 1.0) / 20.0);
      }
    }
  }
  const auto n = static_cast<int>(nodes.cols());
  ops.stiffness.resize(n, n);
  ops.stiffness.setFromTriplets(k_entries.begin(), k_entries.end());
  ops.stiffness.makeCompressed();
  if (consistent_mass) {
    ops.consistent_mass.resize(n, n);
    ops.consistent_mass.setFromTriplets(m_entries.begin(), m_entries.end());
    ops.consistent_mass.makeCompressed();
  }
  return ops;
}

}  // namespace gipsi
