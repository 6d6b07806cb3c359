#include "gipsi/geometry/enclosed_volume.h"

#include <map>
#include <utility>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi {

CavitySurface MakeCavitySurface(const BoundarySurface& boundary, const std::vector<int>& faces) {
  CavitySurface surface;
  std::vector<int> local(static_cast<std::size_t>(boundary.num_vertices()), -1);
  surface.triangles.resize(3, static_cast<Index>(faces.size()));
  for (std::size_t k = 0; k < faces.size(); ++k)
    for (int v = 0; v < 3; ++v) {
      const int bv = boundary.triangles(v, faces[k]);
      int& id = local[static_cast<std::size_t>(bv)];
      if (id < 0) {
        id = static_cast<int>(surface.nodes.size());
        surface.nodes.push_back(boundary.vertex_to_node[static_cast<std::size_t>(bv)]);
      }
      surface.triangles(v == 0 ? 0 : 3 - v, static_cast<Index>(k)) = id;
    }
  return surface;
}

EnclosedVolume::EnclosedVolume(const Triangles& triangles, Index num_vertices)
    : triangles_(triangles), num_vertices_(num_vertices) {
  std::map<std::pair<int, int>, int> half_edges;  // directed edge → count
  for (Index t = 0; t < triangles.cols(); ++t)
    for (int i = 0; i < 3; ++i) {
      const int a = triangles(i, t), b = triangles((i + 1) % 3, t);
      if (a < 0 || a >= num_vertices || b < 0 || b >= num_vertices)
        throw InputError(fmt::format("enclosed volume: triangle {} refers to vertex {} (have {})",
                                     t, a < 0 || a >= num_vertices ? a : b, num_vertices));
      if (++half_edges[{a, b}] > 1)
        throw InputError(fmt::format(
            "enclosed volume: edge {}-{} is used twice in the same direction (inconsistent "
            "orientation or a non-manifold edge)",
            a, b));
    }
  std::map<int, int> next;  // boundary half-edge a → b (no twin b → a)
  for (const auto& [edge, count] : half_edges) {
    (void)count;
    if (half_edges.count({edge.second, edge.first}) != 0) continue;
    if (!next.emplace(edge.first, edge.second).second)
      throw InputError(fmt::format(
          "enclosed volume: vertex {} starts two boundary edges (a non-manifold boundary)",
          edge.first));
  }
  while (!next.empty()) {
    std::vector<std::pair<int, int>> loop;
    const int start = next.begin()->first;
    int a = start;
    while (true) {
      auto it = next.find(a);
      if (it == next.end())
        throw InputError(
            fmt::format("enclosed volume: the boundary through vertex {} is not a closed loop", a));
      const int b = it->second;
      next.erase(it);
      loop.emplace_back(a, b);
      a = b;
      if (a == start) break;
    }
    loops_.push_back(std::move(loop));
  }
}

double EnclosedVolume::Compute(const Points& x, Points* gradient) const {
  GIPSI_CHECK(x.cols() == num_vertices_);
  if (gradient) gradient->setZero(3, num_vertices_);
  double volume = 0;
  for (Index t = 0; t < triangles_.cols(); ++t) {
    const int i0 = triangles_(0, t), i1 = triangles_(1, t), i2 = triangles_(2, t);
    const Vec3 x0 = x.col(i0), x1 = x.col(i1), x2 = x.col(i2);
    volume += x0.dot(x1.cross(x2)) / 6.0;
    if (gradient) {
      gradient->col(i0) += x1.cross(x2) / 6.0;
      gradient->col(i1) += x2.cross(x0) / 6.0;
      gradient->col(i2) += x0.cross(x1) / 6.0;
    }
  }
  for (const auto& loop : loops_) {
    Vec3 c = Vec3::Zero();
    for (const auto& [a, b] : loop) c += x.col(a);
    c /= static_cast<double>(loop.size());
    Vec3 dc = Vec3::Zero();  // ∂V/∂c, shared by the loop's vertices
    for (const auto& [a, b] : loop) {
      // Cap triangle (b, a, c) runs the boundary edge backwards, closing the surface.
      const Vec3 xb = x.col(b), xa = x.col(a);
      volume += xb.dot(xa.cross(c)) / 6.0;
      if (gradient) {
        gradient->col(b) += xa.cross(c) / 6.0;
        gradient->col(a) += c.cross(xb) / 6.0;
        dc += xb.cross(xa) / 6.0;
      }
    }
    if (gradient)
      for (const auto& [a, b] : loop) gradient->col(a) += dc / static_cast<double>(loop.size());
  }
  return volume;
}

}  // namespace gipsi
