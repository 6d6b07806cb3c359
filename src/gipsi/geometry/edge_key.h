#pragma once
/// @file
/// Edges of second-order meshes: the key that names an edge by its two end nodes, and the test
/// that tells a curved edge (its middle node off the midpoint) from a straight one.

#include <algorithm>
#include <cstdint>

#include "gipsi/base/math.h"

namespace gipsi {

/// The edge between nodes a and b, in either order: min·2³² + max (Mesh::SeparateEdgeNodes
/// takes its edges so).
inline std::uint64_t EdgeKey(int a, int b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32) |
         static_cast<std::uint64_t>(std::max(a, b));
}
/// The smaller and the larger end node of an EdgeKey.
inline int EdgeKeyLow(std::uint64_t key) { return static_cast<int>(key >> 32); }
inline int EdgeKeyHigh(std::uint64_t key) { return static_cast<int>(key & 0xffffffffU); }

/// Whether `middle` lies off the midpoint of the edge from `a` to `b` by more than round-off
/// (1e-12 of the edge's length): the edge is curved.
inline bool IsOffMidpoint(const Vec3& a, const Vec3& b, const Vec3& middle) {
  return (middle - 0.5 * (a + b)).norm() > 1e-12 * (b - a).norm();
}

}  // namespace gipsi
