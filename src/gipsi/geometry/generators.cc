/// @file
/// Structured generators: `MakeTetBox` and `MakeTriangleSheet`. The Gmsh shells are in
/// shell_generator.cc.

#include "gipsi/geometry/generators.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"

namespace gipsi {
namespace {

/// Kuhn (Freudenthal) split of the unit cube: for each permutation (p0, p1, p2) of the axes,
/// the tet 0 → e_p0 → e_p0+e_p1 → (1,1,1). Corners are numbered bit 0 = x, bit 1 = y, bit 2 =
/// z. Every cube is cut along its main diagonal and every face along the diagonal through its
/// lowest corner, so neighbouring cubes conform. Odd permutations have their last two nodes
/// swapped to be positively oriented.
constexpr int kKuhnTets[6][4] = {
    {0, 1, 3, 7},  // x, y, z (even)
    {0, 1, 7, 5},  // x, z, y (odd; swapped)
    {0, 2, 7, 3},  // y, x, z (odd; swapped)
    {0, 2, 6, 7},  // y, z, x (even)
    {0, 4, 5, 7},  // z, x, y (even)
    {0, 4, 7, 6},  // z, y, x (odd; swapped)
};

/// Five-tet split: the tet on the four corners of even bit-sum (0, 3, 5, 6) and the four corner
/// tets cut off the odd corners; cells of odd parity use the mirror image (corners XOR 1), so
/// every face diagonal matches its neighbour's.
constexpr int kFiveTets[5][4] = {
    {0, 3, 5, 6}, {1, 0, 3, 5}, {2, 0, 6, 3}, {4, 0, 5, 6}, {7, 3, 6, 5}};

}  // namespace

Mesh MakeTetBox(const Vec3& min, const Vec3& max, const std::array<int, 3>& cells, HexSplit split) {
  if (!min.allFinite() || !max.allFinite() || !(max.array() > min.array()).all())
    ThrowInputError("", "tet box",
                    fmt::format("max ({}, {}, {}) must exceed min ({}, {}, {}) on every axis",
                                max.x(), max.y(), max.z(), min.x(), min.y(), min.z()));
  if (cells[0] < 1 || cells[1] < 1 || cells[2] < 1)
    ThrowInputError("", "tet box",
                    fmt::format("cells must be >= 1 on every axis, got {} x {} x {}", cells[0],
                                cells[1], cells[2]));
  const double num_cells = double(cells[0]) * cells[1] * cells[2];
  if (num_cells * (split == HexSplit::kSix ? 6 : 5) > kMaxGeneratedElements)
    ThrowInputError("", "tet box",
                    fmt::format("{} x {} x {} cells would make more than {:.0e} tets", cells[0],
                                cells[1], cells[2], kMaxGeneratedElements));
  const int nx = cells[0], ny = cells[1], nz = cells[2];
  auto node = [&](int i, int j, int k) { return i + (nx + 1) * (j + (ny + 1) * k); };
  Mesh mesh;
  mesh.nodes.resize(3, Index(nx + 1) * (ny + 1) * (nz + 1));
  const Vec3 h = (max - min).cwiseQuotient(Vec3(nx, ny, nz));
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        // The last layer is placed exactly on `max` (no round-off from min + n·h).
        mesh.nodes.col(node(i, j, k)) =
            Vec3(i == nx ? max.x() : min.x() + i * h.x(), j == ny ? max.y() : min.y() + j * h.y(),
                 k == nz ? max.z() : min.z() + k * h.z());
      }
  const int per_cell = split == HexSplit::kSix ? 6 : 5;
  mesh.tets.resize(4, Index(per_cell) * nx * ny * nz);
  Index e = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        int corner[8];
        for (int c = 0; c < 8; ++c) corner[c] = node(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
        if (split == HexSplit::kSix) {
          for (const auto& tet : kKuhnTets) {
            for (int a = 0; a < 4; ++a) mesh.tets(a, e) = corner[tet[a]];
            ++e;
          }
          continue;
        }
        const int flip = (i + j + k) % 2;  // odd cells mirror x
        for (const auto& tet : kFiveTets) {
          for (int a = 0; a < 4; ++a) mesh.tets(a, e) = corner[tet[a] ^ flip];
          const Vec3 p0 = mesh.nodes.col(mesh.tets(0, e));
          const double vol = (mesh.nodes.col(mesh.tets(1, e)) - p0)
                                 .cross(mesh.nodes.col(mesh.tets(2, e)) - p0)
                                 .dot(mesh.nodes.col(mesh.tets(3, e)) - p0);
          if (vol < 0) std::swap(mesh.tets(2, e), mesh.tets(3, e));
          ++e;
        }
      }

  // Boundary triangles (outward) grouped by the box face they lie on.
  const BoundarySurface boundary = ExtractTetBoundary(mesh.nodes, mesh.tets);
  const char* kFaceNames[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  std::vector<std::vector<int>> by_face(6);
  for (Index t = 0; t < boundary.num_triangles(); ++t) {
    int ijk[3][3];  // [vertex][axis] lattice coordinates
    for (int a = 0; a < 3; ++a) {
      const int n = boundary.vertex_to_node[std::size_t(boundary.triangles(a, t))];
      ijk[a][0] = n % (nx + 1);
      ijk[a][1] = (n / (nx + 1)) % (ny + 1);
      ijk[a][2] = n / ((nx + 1) * (ny + 1));
    }
    for (int face = 0; face < 6; ++face) {
      const int axis = face / 2, value = face % 2 == 0 ? 0 : cells[std::size_t(axis)];
      if (ijk[0][axis] == value && ijk[1][axis] == value && ijk[2][axis] == value) {
        by_face[std::size_t(face)].push_back(int(t));
        break;
      }
    }
  }
  mesh.triangles.resize(3, boundary.num_triangles());
  Index next = 0;
  for (int face = 0; face < 6; ++face) {
    MeshGroup group{kFaceNames[face], 2, {}};
    for (int t : by_face[std::size_t(face)]) {
      for (int a = 0; a < 3; ++a)
        mesh.triangles(a, next) = boundary.vertex_to_node[std::size_t(boundary.triangles(a, t))];
      group.items.push_back(int(next++));
    }
    mesh.groups.push_back(std::move(group));
  }
  GIPSI_CHECK(next == boundary.num_triangles(), "box boundary triangle off the box faces");
  MeshGroup volume{"volume", 3, std::vector<int>(std::size_t(mesh.num_tets()))};
  for (std::size_t i = 0; i < volume.items.size(); ++i) volume.items[i] = int(i);
  mesh.groups.push_back(std::move(volume));
  return mesh;
}

Mesh MakeTriangleSheet(const Vec3& origin, const Vec3& edge_u, const Vec3& edge_v,
                       const std::array<int, 2>& cells) {
  if (cells[0] < 1 || cells[1] < 1)
    ThrowInputError(
        "", "triangle sheet",
        fmt::format("cells must be >= 1 on both axes, got {} x {}", cells[0], cells[1]));
  if (2.0 * cells[0] * cells[1] > kMaxGeneratedElements)
    ThrowInputError("", "triangle sheet",
                    fmt::format("{} x {} cells would make more than {:.0e} triangles", cells[0],
                                cells[1], kMaxGeneratedElements));
  if (!origin.allFinite() || !edge_u.allFinite() || !edge_v.allFinite() ||
      !(edge_u.cross(edge_v).norm() > 1e-12 * edge_u.norm() * edge_v.norm()))
    ThrowInputError(
        "", "triangle sheet",
        fmt::format("edges ({}, {}, {}) and ({}, {}, {}) must be finite, non-zero "
                    "and not parallel",
                    edge_u.x(), edge_u.y(), edge_u.z(), edge_v.x(), edge_v.y(), edge_v.z()));
  const int nu = cells[0], nv = cells[1];
  auto node = [&](int i, int j) { return i + (nu + 1) * j; };
  Mesh mesh;
  mesh.nodes.resize(3, Index(nu + 1) * (nv + 1));
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i)
      mesh.nodes.col(node(i, j)) = origin + (double(i) / nu) * edge_u + (double(j) / nv) * edge_v;
  // Normals along edge_u × edge_v.
  mesh.triangles.resize(3, Index(2) * nu * nv);
  Index t = 0;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      mesh.triangles.col(t++) << node(i, j), node(i + 1, j), node(i + 1, j + 1);
      mesh.triangles.col(t++) << node(i, j), node(i + 1, j + 1), node(i, j + 1);
    }
  MeshGroup u0{"u0", 0, {}}, u1{"u1", 0, {}}, v0{"v0", 0, {}}, v1{"v1", 0, {}};
  for (int j = 0; j <= nv; ++j) {
    u0.items.push_back(node(0, j));
    u1.items.push_back(node(nu, j));
  }
  for (int i = 0; i <= nu; ++i) {
    v0.items.push_back(node(i, 0));
    v1.items.push_back(node(i, nv));
  }
  mesh.groups = {std::move(u0), std::move(u1), std::move(v0), std::move(v1)};
  return mesh;
}

}  // namespace gipsi
