/// @file
/// Scalar P1 operators on tetrahedra.

#include "gipsi/numerics/p1_scalar.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
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

namespace {

// The pattern of every pair of nodes of a tet, column-major with each column's rows sorted (as
// setFromTriplets gives it), built through each node's tets: O(nonzeros) memory, where
// triplets cost 16 bytes per entry per tet (256 bytes per tet and matrix) and a transposed copy.
SparseMatrix P1Pattern(Index num_nodes, const Tets& tets) {
  const auto n = static_cast<std::size_t>(num_nodes);
  const Index num_tets = tets.cols();
  std::vector<int> start(n + 1, 0);
  for (Index e = 0; e < num_tets; ++e)
    for (int a = 0; a < 4; ++a) ++start[static_cast<std::size_t>(tets(a, e)) + 1];
  for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
  std::vector<int> tets_of(static_cast<std::size_t>(start[n]));
  {
    std::vector<int> next(start.begin(), start.end() - 1);
    for (Index e = 0; e < num_tets; ++e)
      for (int a = 0; a < 4; ++a)
        tets_of[static_cast<std::size_t>(next[static_cast<std::size_t>(tets(a, e))]++)] =
            static_cast<int>(e);
  }
  std::vector<int> outer(n + 1, 0), inner, mark(n, -1), column;
  inner.reserve(16 * n);
  for (std::size_t j = 0; j < n; ++j) {
    column.clear();
    for (int k = start[j]; k < start[j + 1]; ++k)
      for (int a = 0; a < 4; ++a) {
        const int i = tets(a, tets_of[static_cast<std::size_t>(k)]);
        if (mark[static_cast<std::size_t>(i)] == static_cast<int>(j)) continue;
        mark[static_cast<std::size_t>(i)] = static_cast<int>(j);
        column.push_back(i);
      }
    std::sort(column.begin(), column.end());
    inner.insert(inner.end(), column.begin(), column.end());
    outer[j + 1] = static_cast<int>(inner.size());
  }
  SparseMatrix m(num_nodes, num_nodes);
  m.resizeNonZeros(static_cast<Index>(inner.size()));
  std::copy(outer.begin(), outer.end(), m.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), m.innerIndexPtr());
  std::fill(m.valuePtr(), m.valuePtr() + inner.size(), 0.0);
  return m;
}

}  // namespace

P1ScalarOperators AssembleP1Scalar(const Points& nodes, const Tets& tets, double length_scale,
                                   const std::function<Mat3(Index)>& diffusivity,
                                   bool consistent_mass) {
  const Points scaled = length_scale * nodes;
  const Index num_tets = tets.cols();
  P1ScalarOperators ops;
  ops.lumped_mass = VecX::Zero(nodes.cols());
  ops.stiffness = P1Pattern(nodes.cols(), tets);
  if (consistent_mass) ops.consistent_mass = ops.stiffness;
  // Each entry is the sum of its tets' contributions in tet order, the first one assigned (as
  // setFromTriplets summed the triplets of each entry in the order given): the same bits.
  std::vector<unsigned char> first(static_cast<std::size_t>(ops.stiffness.nonZeros()), 1);
  const int* outer = ops.stiffness.outerIndexPtr();
  const int* inner = ops.stiffness.innerIndexPtr();
  double* k = ops.stiffness.valuePtr();
  double* m = consistent_mass ? ops.consistent_mass.valuePtr() : nullptr;
  for (Index e = 0; e < num_tets; ++e) {
    double volume = 0;
    const Eigen::Matrix<double, 4, 3> grad = P1Gradients(scaled, tets, e, &volume);
    const Eigen::Matrix4d ke = volume * grad * diffusivity(e) * grad.transpose();
    for (int a = 0; a < 4; ++a) {
      const int ia = tets(a, e);
      ops.lumped_mass[ia] += volume / 4;
      for (int b = 0; b < 4; ++b) {
        const int ib = tets(b, e);
        const auto at = static_cast<std::size_t>(
            std::lower_bound(inner + outer[ib], inner + outer[ib + 1], ia) - inner);
        const double mass = volume * (a == b ? 2.0 : 1.0) / 20.0;
        if (first[at] != 0) {
          first[at] = 0;
          k[at] = ke(a, b);
          if (m != nullptr) m[at] = mass;
        } else {
          k[at] += ke(a, b);
          if (m != nullptr) m[at] += mass;
        }
      }
    }
  }
  return ops;
}

}  // namespace gipsi
