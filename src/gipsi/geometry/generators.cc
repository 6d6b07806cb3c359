/// @file
/// Structured generators: `MakeTetBox` and `MakeTriangleSheet`. The Gmsh shells are in
/// shell_generator.cc.

#include "gipsi/geometry/generators.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/mesh_block.h"

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

// The lattice of a structured box (MakeTetBox): its nodes' positions and each tet's corners,
// computed from the indices alone, so a block of the box is made without the whole.
class BoxLattice {
 public:
  BoxLattice(const Vec3& min, const Vec3& max, const std::array<int, 3>& cells, HexSplit split)
      : min_(min), max_(max), n_(cells), per_cell_(split == HexSplit::kSix ? 6 : 5) {
    if (!min.allFinite() || !max.allFinite() || !(max.array() > min.array()).all())
      ThrowInputError("", "tet box",
                      fmt::format("max ({}, {}, {}) must exceed min ({}, {}, {}) on every axis",
                                  max.x(), max.y(), max.z(), min.x(), min.y(), min.z()));
    if (cells[0] < 1 || cells[1] < 1 || cells[2] < 1)
      ThrowInputError("", "tet box",
                      fmt::format("cells must be >= 1 on every axis, got {} x {} x {}", cells[0],
                                  cells[1], cells[2]));
    const double num_cells = double(cells[0]) * cells[1] * cells[2];
    if (num_cells * per_cell_ > kMaxGeneratedElements)
      ThrowInputError("", "tet box",
                      fmt::format("{} x {} x {} cells would make more than {:.0e} tets", cells[0],
                                  cells[1], cells[2], kMaxGeneratedElements));
    h_ = (max - min).cwiseQuotient(Vec3(n_[0], n_[1], n_[2]));
  }

  [[nodiscard]] Index num_nodes() const { return Index(n_[0] + 1) * (n_[1] + 1) * (n_[2] + 1); }
  [[nodiscard]] Index num_tets() const { return Index(per_cell_) * n_[0] * n_[1] * n_[2]; }
  [[nodiscard]] int node(int i, int j, int k) const {
    return i + (n_[0] + 1) * (j + (n_[1] + 1) * k);
  }
  /// Lattice coordinate of node n along `axis`.
  [[nodiscard]] int lattice(int n, int axis) const {
    if (axis == 0) return n % (n_[0] + 1);
    if (axis == 1) return (n / (n_[0] + 1)) % (n_[1] + 1);
    return n / ((n_[0] + 1) * (n_[1] + 1));
  }
  [[nodiscard]] int cells(int axis) const { return n_[std::size_t(axis)]; }
  /// Node n's position; the last layer lies exactly on `max` (no round-off from min + n·h).
  [[nodiscard]] Vec3 position(int n) const {
    Vec3 p;
    for (int a = 0; a < 3; ++a) {
      const int l = lattice(n, a);
      p[a] = l == n_[std::size_t(a)] ? max_[a] : min_[a] + l * h_[a];
    }
    return p;
  }
  /// The corners of tet e, positively oriented.
  void Tet(Index e, int corners[4]) const {
    const Index cell = e / per_cell_;
    const int t = int(e % per_cell_);
    const int i = int(cell % n_[0]), j = int((cell / n_[0]) % n_[1]);
    const int k = int(cell / (Index(n_[0]) * n_[1]));
    int corner[8];
    for (int c = 0; c < 8; ++c) corner[c] = node(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
    if (per_cell_ == 6) {
      for (int a = 0; a < 4; ++a) corners[a] = corner[kKuhnTets[t][a]];
      return;
    }
    const int flip = (i + j + k) % 2;  // odd cells mirror x
    for (int a = 0; a < 4; ++a) corners[a] = corner[kFiveTets[t][a] ^ flip];
    const Vec3 p0 = position(corners[0]);
    const double vol =
        (position(corners[1]) - p0).cross(position(corners[2]) - p0).dot(position(corners[3]) - p0);
    if (vol < 0) std::swap(corners[2], corners[3]);
  }
  /// The boundary triangles of the cells before cell `cell` (each box face of a cell is cut
  /// into two triangles by either split).
  [[nodiscard]] std::int64_t TrianglesOfCellsBefore(Index cell) const {
    std::int64_t count = 0;
    for (Index c = 0; c < cell; ++c) {
      const int i = int(c % n_[0]), j = int((c / n_[0]) % n_[1]);
      const int k = int(c / (Index(n_[0]) * n_[1]));
      count += 2 * ((i == 0) + (i == n_[0] - 1) + (j == 0) + (j == n_[1] - 1) + (k == 0) +
                    (k == n_[2] - 1));
    }
    return count;
  }
  [[nodiscard]] int per_cell() const { return per_cell_; }

 private:
  Vec3 min_, max_, h_;
  std::array<int, 3> n_;
  int per_cell_;
};

const char* const kBoxFaceNames[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};

// The box face (0..5: xmin, xmax, ...) that the three nodes lie on, or -1.
int BoxFaceOf(const BoxLattice& box, const int (&n)[3]) {
  for (int face = 0; face < 6; ++face) {
    const int axis = face / 2, value = face % 2 == 0 ? 0 : box.cells(axis);
    if (box.lattice(n[0], axis) == value && box.lattice(n[1], axis) == value &&
        box.lattice(n[2], axis) == value)
      return face;
  }
  return -1;
}

}  // namespace

Mesh MakeTetBox(const Vec3& min, const Vec3& max, const std::array<int, 3>& cells, HexSplit split) {
  const BoxLattice box(min, max, cells, split);
  Mesh mesh;
  mesh.nodes.resize(3, box.num_nodes());
  for (Index n = 0; n < box.num_nodes(); ++n) mesh.nodes.col(n) = box.position(int(n));
  mesh.tets.resize(4, box.num_tets());
  for (Index e = 0; e < box.num_tets(); ++e) {
    int corners[4];
    box.Tet(e, corners);
    for (int a = 0; a < 4; ++a) mesh.tets(a, e) = corners[a];
  }

  // Boundary triangles (outward) grouped by the box face they lie on.
  const BoundarySurface boundary = ExtractTetBoundary(mesh.nodes, mesh.tets);
  std::vector<std::vector<int>> by_face(6);
  for (Index t = 0; t < boundary.num_triangles(); ++t) {
    int n[3];
    for (int a = 0; a < 3; ++a)
      n[a] = boundary.vertex_to_node[std::size_t(boundary.triangles(a, t))];
    const int face = BoxFaceOf(box, n);
    if (face >= 0) by_face[std::size_t(face)].push_back(int(t));
  }
  mesh.triangles.resize(3, boundary.num_triangles());
  Index next = 0;
  for (int face = 0; face < 6; ++face) {
    MeshGroup group{kBoxFaceNames[face], 2, {}};
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

MeshBlock MakeTetBoxBlock(const Vec3& min, const Vec3& max, const std::array<int, 3>& cells,
                          HexSplit split, int rank, int size) {
  const BoxLattice box(min, max, cells, split);
  GIPSI_CHECK(size >= 1 && rank >= 0 && rank < size);
  MeshBlock block;
  block.rank = rank;
  block.size = size;
  block.num_nodes = box.num_nodes();
  block.num_tets = box.num_tets();
  const std::int64_t nx = cells[0], ny = cells[1], nz = cells[2];
  block.num_triangles = 4 * (nx * ny + ny * nz + nx * nz);
  const Index node_begin = block.node_begin(),
              node_end = BlockBegin(block.num_nodes, rank + 1, size);
  block.nodes.resize(3, node_end - node_begin);
  for (Index n = node_begin; n < node_end; ++n)
    block.nodes.col(n - node_begin) = box.position(int(n));
  const Index tet_begin = block.tet_begin(), tet_end = BlockBegin(block.num_tets, rank + 1, size);
  block.tets.resize(4, tet_end - tet_begin);
  // The triangles of the tets before this block: whole cells counted, then the partial one.
  const Index first_cell = tet_begin / box.per_cell();
  std::int64_t before = box.TrianglesOfCellsBefore(first_cell);
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> face_of;
  for (Index e = first_cell * box.per_cell(); e < tet_end; ++e) {
    int corners[4];
    box.Tet(e, corners);
    if (e >= tet_begin)
      for (int a = 0; a < 4; ++a) block.tets(a, e - tet_begin) = corners[a];
    for (int skip = 0; skip < 4; ++skip) {
      int n[3], k = 0;
      for (int a = 0; a < 4; ++a)
        if (a != skip) n[k++] = corners[a];
      const int face = BoxFaceOf(box, n);
      if (face < 0) continue;
      if (e < tet_begin) {
        ++before;
        continue;
      }
      // Outward: away from the tet's fourth corner.
      const Vec3 p0 = box.position(n[0]);
      if ((box.position(n[1]) - p0)
              .cross(box.position(n[2]) - p0)
              .dot(box.position(corners[skip]) - p0) > 0)
        std::swap(n[1], n[2]);
      triangles.push_back({n[0], n[1], n[2]});
      face_of.push_back(face);
    }
  }
  block.first_triangle = before;
  block.triangles.resize(3, Index(triangles.size()));
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int a = 0; a < 3; ++a) block.triangles(a, Index(t)) = triangles[t][std::size_t(a)];
  for (int face = 0; face < 6; ++face) {
    MeshGroup group{kBoxFaceNames[face], 2, {}};
    for (std::size_t t = 0; t < face_of.size(); ++t)
      if (face_of[t] == face) group.items.push_back(int(before + std::int64_t(t)));
    block.groups.push_back(std::move(group));
  }
  MeshGroup volume{"volume", 3, std::vector<int>(std::size_t(tet_end - tet_begin))};
  for (std::size_t i = 0; i < volume.items.size(); ++i) volume.items[i] = int(tet_begin + Index(i));
  block.groups.push_back(std::move(volume));
  return block;
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
