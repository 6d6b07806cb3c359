#include "gipsi/collision/tool_surface.h"

#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi {

Mesh MakeCapsuleSurface(double radius, double length, int segments) {
  if (!(radius > 0) || !(length >= 0) || segments < 3)
    throw InputError(fmt::format(
        "capsule surface: need radius > 0, length >= 0 and segments >= 3 (got {}, {}, {})", radius,
        length, segments));
  const int rings = std::max(2, segments / 2);  // per hemisphere, pole excluded
  // Latitude rows from the bottom pole (θ = π) to the top pole (θ = 0): 2 * rings − 1 rows of
  // `segments` vertices; the equator row is duplicated when length > 0 (one per hemisphere).
  std::vector<Vec3> v;
  v.emplace_back(0, 0, -radius);
  std::vector<int> row_start;
  auto add_row = [&](double theta, double z_shift) {
    row_start.push_back(static_cast<int>(v.size()));
    for (int k = 0; k < segments; ++k) {
      const double phi = 2 * std::numbers::pi * k / segments;
      v.emplace_back(radius * std::sin(theta) * std::cos(phi),
                     radius * std::sin(theta) * std::sin(phi), radius * std::cos(theta) + z_shift);
    }
  };
  for (int r = 1; r <= rings; ++r)
    add_row(std::numbers::pi - 0.5 * std::numbers::pi * r / rings, 0);
  for (int r = length > 0 ? 0 : 1; r < rings; ++r)
    add_row(0.5 * std::numbers::pi - 0.5 * std::numbers::pi * r / rings, length);
  v.emplace_back(0, 0, radius + length);
  const int top = static_cast<int>(v.size()) - 1;

  std::vector<std::array<int, 3>> tris;
  for (int k = 0; k < segments; ++k) {  // bottom cap, normals pointing down
    const int a = row_start.front() + k, b = row_start.front() + (k + 1) % segments;
    tris.push_back({0, b, a});
  }
  for (std::size_t r = 0; r + 1 < row_start.size(); ++r)
    for (int k = 0; k < segments; ++k) {
      const int a = row_start[r] + k, b = row_start[r] + (k + 1) % segments;
      const int c = row_start[r + 1] + k, d = row_start[r + 1] + (k + 1) % segments;
      tris.push_back({a, b, d});
      tris.push_back({a, d, c});
    }
  for (int k = 0; k < segments; ++k) {
    const int a = row_start.back() + k, b = row_start.back() + (k + 1) % segments;
    tris.push_back({a, b, top});
  }
  Mesh mesh;
  mesh.nodes.resize(3, static_cast<Index>(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) mesh.nodes.col(static_cast<Index>(i)) = v[i];
  mesh.triangles.resize(3, static_cast<Index>(tris.size()));
  for (std::size_t t = 0; t < tris.size(); ++t)
    mesh.triangles.col(static_cast<Index>(t)) << tris[t][0], tris[t][1], tris[t][2];
  return mesh;
}

}  // namespace gipsi
