#include "gipsi/collision/collision_surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "gipsi/base/error.h"

namespace gipsi {

CollisionSurface::CollisionSurface(Triangles triangles, Index num_vertices, bool closed)
    : triangles_(std::move(triangles)), closed_(closed), positions_(Points::Zero(3, num_vertices)) {
  const Index T = triangles_.cols();
  GIPSI_CHECK(T == 0 || (triangles_.minCoeff() >= 0 && triangles_.maxCoeff() < num_vertices),
              "triangle vertex out of range");
  // Edges: (lo, hi, triangle, slot) sorted; equal (lo, hi) runs are one edge.
  std::vector<std::array<int, 4>> half;
  half.reserve(static_cast<std::size_t>(3 * T));
  for (Index t = 0; t < T; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles_(k, t), b = triangles_((k + 1) % 3, t);
      half.push_back({std::min(a, b), std::max(a, b), static_cast<int>(t), k});
    }
  std::sort(half.begin(), half.end());
  tri_edges_.resize(3, T);
  std::vector<std::array<int, 2>> edges;
  for (std::size_t i = 0; i < half.size(); ++i) {
    if (i == 0 || half[i][0] != half[i - 1][0] || half[i][1] != half[i - 1][1]) {
      edges.push_back({half[i][0], half[i][1]});
      edge_owner_.push_back(half[i][2]);  // sorted by triangle within a run: the lowest id
    }
    tri_edges_(half[i][3], half[i][2]) = static_cast<int>(edges.size() - 1);
  }
  edges_.resize(2, static_cast<Index>(edges.size()));
  for (std::size_t e = 0; e < edges.size(); ++e)
    edges_.col(static_cast<Index>(e)) << edges[e][0], edges[e][1];
  vertex_owner_.assign(static_cast<std::size_t>(num_vertices), -1);
  for (Index t = T; t-- > 0;)
    for (int k = 0; k < 3; ++k) vertex_owner_[static_cast<std::size_t>(triangles_(k, t))] = int(t);
  owned_.assign(static_cast<std::size_t>(T), 0);
  for (Index t = 0; t < T; ++t)
    for (int k = 0; k < 3; ++k) {
      if (vertex_owner_[static_cast<std::size_t>(triangles_(k, t))] == t)
        owned_[static_cast<std::size_t>(t)] |= static_cast<std::uint8_t>(1u << k);
      if (edge_owner_[static_cast<std::size_t>(tri_edges_(k, t))] == t)
        owned_[static_cast<std::size_t>(t)] |= static_cast<std::uint8_t>(1u << (3 + k));
    }
  face_normals_.resize(3, T);
}

const Box3& CollisionSurface::bounds() const {
  return tree_.empty() ? empty_box_ : tree_.nodes().front().box;
}

void CollisionSurface::Update(double rebuild_ratio, bool cones) {
  if (tree_.num_builds() == 0) {
    tree_.Build(positions_, triangles_);
  } else {
    tree_.Update(positions_, triangles_, rebuild_ratio);
  }
  const Index T = triangles_.cols();
  // Scalar code on the raw columns: Eigen's expressions on unaligned 3-vectors cost twice the
  // instructions here. One division and three products instead of three divisions: the
  // divider, shared with the square root, bounded this loop.
  const double* x = positions_.data();
  double* normal = face_normals_.data();
  for (Index t = 0; t < T; ++t, normal += 3) {
    const double* a = x + 3 * static_cast<std::ptrdiff_t>(triangles_(0, t));
    const double* b = x + 3 * static_cast<std::ptrdiff_t>(triangles_(1, t));
    const double* c = x + 3 * static_cast<std::ptrdiff_t>(triangles_(2, t));
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                         u[0] * v[1] - u[1] * v[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const double inv = len > 0 ? 1.0 / len : 0.0;
    for (int k = 0; k < 3; ++k) normal[k] = inv * n[k];
  }
  if (!cones) return;
  vertex_normals_.setZero(3, positions_.cols());
  edge_normals_.setZero(3, edges_.cols());
  for (Index t = 0; t < T; ++t)
    for (int k = 0; k < 3; ++k) {
      vertex_normals_.col(triangles_(k, t)) += face_normals_.col(t);
      edge_normals_.col(tri_edges_(k, t)) += face_normals_.col(t);
    }
  for (Index v = 0; v < vertex_normals_.cols(); ++v) vertex_normals_.col(v).normalize();
  for (Index e = 0; e < edge_normals_.cols(); ++e) edge_normals_.col(e).normalize();
  // A triangle's cone holds its face normal and the normals of its vertices and edges: the
  // normals the self-collision "facing" test uses for features of this triangle.
  tri_cones_.resize(static_cast<std::size_t>(T));
  for (Index t = 0; t < T; ++t) {
    const Vec3 axis = face_normals_.col(t);
    double min_dot = axis.squaredNorm() > 0 ? 1.0 : -1.0;
    for (int k = 0; k < 3; ++k) {
      min_dot = std::min(min_dot, axis.dot(vertex_normals_.col(triangles_(k, t))));
      min_dot = std::min(min_dot, axis.dot(edge_normals_.col(tri_edges_(k, t))));
    }
    const double half = std::acos(std::clamp(min_dot, -1.0, 1.0)) + 1e-9;
    tri_cones_[static_cast<std::size_t>(t)] = {axis, std::min(half, std::numbers::pi)};
  }
  tree_.RefitCones(tri_cones_);
}

}  // namespace gipsi
