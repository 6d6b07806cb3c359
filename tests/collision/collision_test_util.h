#pragma once
// Builders shared by the collision tests.

#include <cmath>

#include "gipsi/collision/collision_surface.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/generators.h"

namespace gipsi::testing_util {

/// A flat n×n-cell sheet on [x0, x0 + size]×[y0, y0 + size] at height z (open surface).
inline CollisionSurface Sheet(int n, double size, const Vec3& origin) {
  Mesh m = MakeTriangleSheet(origin, Vec3(size, 0, 0), Vec3(0, size, 0), {n, n});
  CollisionSurface s(m.triangles, m.num_nodes(), false);
  s.positions() = m.nodes;
  return s;
}

/// The closed boundary surface of a tet box (outward triangles).
inline CollisionSurface BoxSurface(const Vec3& lo, const Vec3& hi, int cells) {
  Mesh m = MakeTetBox(lo, hi, {cells, cells, cells});
  BoundarySurface b = ExtractTetBoundary(m.nodes, m.tets);
  CollisionSurface s(b.triangles, b.num_vertices(), true);
  b.Gather(m.nodes, s.positions());
  return s;
}

}  // namespace gipsi::testing_util
