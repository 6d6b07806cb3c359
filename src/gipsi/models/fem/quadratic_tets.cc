#include "gipsi/models/fem/quadratic_tets.h"

#include <algorithm>
#include <utility>

#include "gipsi/base/error.h"
#include "gipsi/geometry/edge_key.h"

namespace gipsi {

int QuadraticTets::EdgeNode(int a, int b) const {
  const auto it = edge_index.find(EdgeKey(a, b));
  return it == edge_index.end() ? -1 : it->second;
}

QuadraticTets ElevateToQuadratic(const Mesh& mesh) {
  if (mesh.num_tets() == 0)
    throw InputError("quadratic elements need a tetrahedral mesh; this mesh has no tets");
  QuadraticTets q;
  q.num_vertices = mesh.num_nodes();
  const Index ne = mesh.num_tets();
  q.elements.resize(10, ne);
  std::vector<std::array<int, 2>> edges;
  edges.reserve(static_cast<std::size_t>(7 * ne / 5 + 16));  // about 1.2 edges per tet
  q.edge_index.reserve(edges.capacity());
  for (Index e = 0; e < ne; ++e) {
    for (int a = 0; a < 4; ++a) q.elements(a, e) = mesh.tets(a, e);
    for (int k = 0; k < 6; ++k) {
      const int va = mesh.tets(kTetEdges[k][0], e), vb = mesh.tets(kTetEdges[k][1], e);
      const int next = static_cast<int>(q.num_vertices) + static_cast<int>(edges.size());
      const auto [it, inserted] = q.edge_index.emplace(EdgeKey(va, vb), next);
      if (inserted) edges.push_back({std::min(va, vb), std::max(va, vb)});
      q.elements(4 + k, e) = it->second;
    }
  }
  q.edges.resize(2, static_cast<Index>(edges.size()));
  q.rest.resize(3, q.num_vertices + static_cast<Index>(edges.size()));
  q.rest.leftCols(q.num_vertices) = mesh.nodes;
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const auto col = static_cast<Index>(k);
    q.edges(0, col) = edges[k][0];
    q.edges(1, col) = edges[k][1];
    q.rest.col(q.num_vertices + col) =
        0.5 * (mesh.nodes.col(edges[k][0]) + mesh.nodes.col(edges[k][1]));
  }
  // Curved edges of a second-order mesh: a middle node off the straight midpoint by more than
  // round-off (1e-12 of the edge's length) moves the edge node there.
  std::vector<std::uint8_t> curved_edge(edges.size(), 0);
  for (Index k = 0; k < mesh.edge_node_ends.cols(); ++k) {
    const int node = q.EdgeNode(mesh.edge_node_ends(0, k), mesh.edge_node_ends(1, k));
    if (node < 0) continue;  // an edge of triangles only
    const Vec3 middle = mesh.edge_nodes.col(k);
    if (!IsOffMidpoint(mesh.nodes.col(mesh.edge_node_ends(0, k)),
                       mesh.nodes.col(mesh.edge_node_ends(1, k)), middle))
      continue;
    q.rest.col(node) = middle;
    curved_edge[static_cast<std::size_t>(node - q.num_vertices)] = 1;
    ++q.num_curved_edges;
  }
  if (q.num_curved_edges > 0) {
    q.curved.assign(static_cast<std::size_t>(ne), 0);
    for (Index e = 0; e < ne; ++e)
      for (int k = 0; k < 6; ++k)
        if (curved_edge[static_cast<std::size_t>(q.elements(4 + k, e) - q.num_vertices)])
          q.curved[static_cast<std::size_t>(e)] = 1;
  }
  return q;
}

bool QuadraticTets::IsCurved(Index e) const {
  return !curved.empty() && curved[static_cast<std::size_t>(e)] != 0;
}

Eigen::Matrix<double, 10, 1> QuadraticTetShape(const Eigen::Vector4d& L) {
  Eigen::Matrix<double, 10, 1> n;
  for (int a = 0; a < 4; ++a) n[a] = L[a] * (2 * L[a] - 1);
  for (int k = 0; k < 6; ++k) n[4 + k] = 4 * L[kTetEdges[k][0]] * L[kTetEdges[k][1]];
  return n;
}

Eigen::Matrix<double, 10, 4> QuadraticTetShapeDerivatives(const Eigen::Vector4d& L) {
  Eigen::Matrix<double, 10, 4> d = Eigen::Matrix<double, 10, 4>::Zero();
  for (int a = 0; a < 4; ++a) d(a, a) = 4 * L[a] - 1;
  for (int k = 0; k < 6; ++k) {
    const int i = kTetEdges[k][0], j = kTetEdges[k][1];
    d(4 + k, i) = 4 * L[j];
    d(4 + k, j) = 4 * L[i];
  }
  return d;
}

Eigen::Matrix<double, 6, 1> QuadraticTriangleShape(const Vec3& L) {
  Eigen::Matrix<double, 6, 1> n;
  for (int a = 0; a < 3; ++a) n[a] = L[a] * (2 * L[a] - 1);
  for (int k = 0; k < 3; ++k) n[3 + k] = 4 * L[kTriangleEdges[k][0]] * L[kTriangleEdges[k][1]];
  return n;
}

Eigen::Matrix<double, 6, 2> QuadraticTriangleParamDerivatives(const Vec3& L) {
  // ∂/∂ξ = ∂/∂L_1 − ∂/∂L_0 and ∂/∂η = ∂/∂L_2 − ∂/∂L_0 for L = (1 − ξ − η, ξ, η).
  Eigen::Matrix<double, 6, 3> dl = Eigen::Matrix<double, 6, 3>::Zero();
  for (int a = 0; a < 3; ++a) dl(a, a) = 4 * L[a] - 1;
  for (int k = 0; k < 3; ++k) {
    const int i = kTriangleEdges[k][0], j = kTriangleEdges[k][1];
    dl(3 + k, i) = 4 * L[j];
    dl(3 + k, j) = 4 * L[i];
  }
  Eigen::Matrix<double, 6, 2> d;
  d.col(0) = dl.col(1) - dl.col(0);
  d.col(1) = dl.col(2) - dl.col(0);
  return d;
}

const TetQuadrature& TetRuleDegree2() {
  static const TetQuadrature rule = [] {
    // Points (a, b, b, b) and permutations, a = (5 + 3√5)/20, b = (5 − √5)/20.
    const double a = 0.5854101966249685, b = 0.1381966011250105;
    TetQuadrature r;
    for (int k = 0; k < 4; ++k) {
      Eigen::Vector4d p = Eigen::Vector4d::Constant(b);
      p[k] = a;
      r.points.push_back(p);
      r.weights.push_back(0.25);
    }
    return r;
  }();
  return rule;
}

const TetQuadrature& TetRuleDegree7() {
  static const TetQuadrature rule = [] {
    // Conical product (Stroud 1971, §2.4): the unit tet as the image of the unit cube under
    // x = a, y = (1 − a) b, z = (1 − a)(1 − b) c, Jacobian (1 − a)² (1 − b), with 5-point
    // Gauss–Legendre rules in a, b and c. A polynomial of degree p on the tet becomes one of
    // degree p + 2, p + 1 and p in a, b and c; the 5-point rule is exact to degree 9, so the
    // product is exact for p ≤ 7.
    const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                         0.9061798459386640};
    const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                         0.4786286704993665, 0.2369268850561891};
    TetQuadrature r;
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j)
        for (int k = 0; k < 5; ++k) {
          const double a = 0.5 * (x[i] + 1), b = 0.5 * (x[j] + 1), c = 0.5 * (x[k] + 1);
          const double px = a, py = (1 - a) * b, pz = (1 - a) * (1 - b) * c;
          r.points.emplace_back(1 - px - py - pz, px, py, pz);
          // The cube's weights (each halved for [0, 1]) times the Jacobian, times 6 (the unit
          // tet's volume is 1/6) so that they sum to 1.
          r.weights.push_back(6 * 0.125 * w[i] * w[j] * w[k] * (1 - a) * (1 - a) * (1 - b));
        }
    return r;
  }();
  return rule;
}

const TriangleQuadrature& TriangleRuleDegree4() {
  static const TriangleQuadrature rule = [] {
    TriangleQuadrature r;
    const std::pair<double, double> orbits[2] = {{0.445948490915965, 0.223381589678011},
                                                 {0.091576213509771, 0.109951743655322}};
    for (const auto& [s, w] : orbits) {
      for (int k = 0; k < 3; ++k) {
        Vec3 p = Vec3::Constant(s);
        p[k] = 1 - 2 * s;
        r.points.push_back(p);
        r.weights.push_back(w);
      }
    }
    return r;
  }();
  return rule;
}

}  // namespace gipsi
