#include "gipsi/geometry/generators.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cstdint>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/geometry/normals.h"
#include "gipsi/geometry/quality.h"

namespace gipsi {
namespace {

using ::testing::SizeIs;
using ::testing::StrEq;
using ::testing::ThrowsMessage;

TEST(TetBox, TetsArePositiveAndFillTheBox) {
  const Vec3 lo(-1, 2, 0.5), hi(1, 3, 2);
  const Mesh box = MakeTetBox(lo, hi, {4, 3, 2});
  EXPECT_NO_THROW(box.Validate("box"));
  EXPECT_EQ(box.num_nodes(), 5 * 4 * 3);
  EXPECT_EQ(box.num_tets(), 6 * 4 * 3 * 2);
  const TetQualityReport report = CheckTetQuality(box.nodes, box.tets);
  EXPECT_GT(report.min_volume, 0);
  EXPECT_NEAR(report.total_volume, (hi - lo).prod(), 1e-13);
}

TEST(TetBox, NodesFollowTheLatticeNumbering) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(2, 3, 4), {2, 3, 4});
  for (int k = 0; k <= 4; ++k)
    for (int j = 0; j <= 3; ++j)
      for (int i = 0; i <= 2; ++i) EXPECT_EQ(box.nodes.col(i + 3 * (j + 4 * k)), Vec3(i, j, k));
}

TEST(TetBox, NeighbouringCellsConform) {
  // Non-matching face diagonals between cells would leave interior faces on the boundary.
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {3, 3, 3});
  EXPECT_EQ(ExtractTetBoundary(box.nodes, box.tets).num_triangles(), 6 * 3 * 3 * 2);
}

TEST(TetBox, BoundaryGroupsCoverEachFaceOutward) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 3, 4});
  const Points normals = FaceNormals(box.nodes, box.triangles);
  const char* names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  const int quads[3] = {3 * 4, 2 * 4, 2 * 3};  // cells on the faces normal to x, y, z
  Index total = 0;
  for (int f = 0; f < 6; ++f) {
    const MeshGroup* group = box.FindGroup(names[f]);
    ASSERT_NE(group, nullptr) << names[f];
    EXPECT_EQ(group->dim, 2);
    EXPECT_THAT(group->items, SizeIs(2 * quads[f / 2])) << names[f];
    Vec3 outward = Vec3::Zero();
    outward[f / 2] = f % 2 == 0 ? -1 : 1;
    for (int t : group->items) EXPECT_EQ(normals.col(t), outward) << names[f];
    total += Index(group->items.size());
  }
  EXPECT_EQ(total, box.num_triangles());
  const MeshGroup* volume = box.FindGroup("volume");
  ASSERT_NE(volume, nullptr);
  EXPECT_EQ(volume->dim, 3);
  EXPECT_THAT(volume->items, SizeIs(box.num_tets()));
}

TEST(TetBox, RejectsAnEmptyBoxAndZeroCells) {
  EXPECT_THAT(
      [] {
        MakeTetBox(Vec3(0, 0, 0), Vec3(1, 0, 1), {1, 1, 1});
      },
      ThrowsMessage<InputError>(
          StrEq("tet box: max (1, 0, 1) must exceed min (0, 0, 0) on every axis")));
  EXPECT_THAT(
      [] {
        MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 0, 1});
      },
      ThrowsMessage<InputError>(StrEq("tet box: cells must be >= 1 on every axis, got 1 x 0 x 1")));
}

TEST(TriangleSheet, SpansTheParallelogramWithNormalsAlongUCrossV) {
  const Vec3 origin(1, 1, 1), u(2, 0, 0), v(0.5, 0, 3);
  const Mesh sheet = MakeTriangleSheet(origin, u, v, {4, 3});
  EXPECT_NO_THROW(sheet.Validate("sheet"));
  EXPECT_EQ(sheet.num_nodes(), 5 * 4);
  EXPECT_EQ(sheet.num_triangles(), 2 * 4 * 3);
  EXPECT_EQ(sheet.num_tets(), 0);
  EXPECT_LT((sheet.nodes.col(4 + 5 * 3) - (origin + u + v)).norm(), 1e-15);
  EXPECT_NEAR(TriangleAreas(sheet.nodes, sheet.triangles).sum(), u.cross(v).norm(), 1e-13);
  const Points normals = FaceNormals(sheet.nodes, sheet.triangles);
  for (Index t = 0; t < normals.cols(); ++t)
    EXPECT_LT((normals.col(t) - u.cross(v).normalized()).norm(), 1e-14);
}

TEST(TriangleSheet, EdgeGroupsHoldTheEdgeNodes) {
  const Mesh sheet = MakeTriangleSheet(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), {4, 3});
  const struct {
    const char* name;
    int axis;
    double value;
    std::size_t count;
  } edges[] = {{"u0", 0, 0, 4}, {"u1", 0, 1, 4}, {"v0", 1, 0, 5}, {"v1", 1, 1, 5}};
  for (const auto& edge : edges) {
    const MeshGroup* group = sheet.FindGroup(edge.name);
    ASSERT_NE(group, nullptr) << edge.name;
    EXPECT_EQ(group->dim, 0);
    EXPECT_THAT(group->items, SizeIs(edge.count)) << edge.name;
    for (int n : group->items) EXPECT_EQ(sheet.nodes(edge.axis, n), edge.value) << edge.name;
  }
}

TEST(TriangleSheet, RejectsParallelEdgesAndZeroCells) {
  EXPECT_THAT(
      [] {
        MakeTriangleSheet(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0), {1, 1});
      },
      ThrowsMessage<InputError>(StrEq("triangle sheet: edges (1, 0, 0) and (2, 0, 0) "
                                      "must be finite, non-zero and not parallel")));
  EXPECT_THAT(
      [] {
        MakeTriangleSheet(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), {0, 1});
      },
      ThrowsMessage<InputError>(
          StrEq("triangle sheet: cells must be >= 1 on both axes, got 0 x 1")));
}

}  // namespace
}  // namespace gipsi

namespace gipsi {
namespace {

TEST(TetBox, FiveTetSplitConformsAndFillsTheBox) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(2, 3, 1), {3, 4, 2}, HexSplit::kFive);
  EXPECT_EQ(box.num_tets(), 5 * 3 * 4 * 2);
  double volume = 0;
  for (Index e = 0; e < box.num_tets(); ++e) {
    const double v = TetSignedVolume(box.nodes.col(box.tets(0, e)), box.nodes.col(box.tets(1, e)),
                                     box.nodes.col(box.tets(2, e)), box.nodes.col(box.tets(3, e)));
    ASSERT_GT(v, 0) << "tet " << e;
    volume += v;
  }
  EXPECT_NEAR(volume, 6.0, 1e-12);
  // Conforming: every boundary face of the tet set lies on the box surface (a mismatched face
  // diagonal between neighbouring cells would leave interior faces used once).
  const BoundarySurface b = ExtractTetBoundary(box.nodes, box.tets);
  EXPECT_EQ(b.num_triangles(), 2 * 2 * (3 * 4 + 3 * 2 + 4 * 2));
}

// Absurd sizes are refused before any allocation (a fuzzed scene must not exhaust memory).
TEST(Generators, RefuseAbsurdSizes) {
  EXPECT_THROW((void)MakeTetBox(Vec3::Zero(), Vec3::Ones(), {100000, 100000, 100000}), InputError);
  EXPECT_THROW(
      (void)MakeTriangleSheet(Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY(), {100000, 100000}),
      InputError);
}

}  // namespace
}  // namespace gipsi

namespace gipsi {
namespace {

// Outward boundary triangles as node triples rotated to start at their smallest node, with the
// name of the group each is in.
using NamedTriangle = std::tuple<int, int, int, std::string>;

NamedTriangle Named(const Triangles& triangles, Index t, std::int64_t first,
                    const std::vector<MeshGroup>& groups) {
  std::array<int, 3> n{triangles(0, t), triangles(1, t), triangles(2, t)};
  std::rotate(n.begin(), std::min_element(n.begin(), n.end()), n.end());
  std::string name;
  for (const MeshGroup& g : groups)
    if (g.dim == 2 &&
        std::find(g.items.begin(), g.items.end(), static_cast<int>(first + t)) != g.items.end())
      name = g.name;
  return {n[0], n[1], n[2], name};
}

// The blocks of a box, made one by one without the whole, put back together are the box: its
// nodes and tets in order, its outward boundary triangles in their groups, each once.
TEST(TetBoxBlock, TheBlocksTogetherAreTheWholeBox) {
  for (HexSplit split : {HexSplit::kSix, HexSplit::kFive}) {
    const Vec3 min(0, -1, 2), max(3, 1, 3);
    const std::array<int, 3> cells{7, 3, 2};
    const Mesh whole = MakeTetBox(min, max, cells, split);
    std::multiset<NamedTriangle> expected, got;
    for (Index t = 0; t < whole.num_triangles(); ++t)
      expected.insert(Named(whole.triangles, t, 0, whole.groups));
    const int size = 5;
    Points nodes(3, 0);
    Tets tets(4, 0);
    std::int64_t next_triangle = 0;
    std::int64_t volume = 0;
    for (int rank = 0; rank < size; ++rank) {
      const MeshBlock block = MakeTetBoxBlock(min, max, cells, split, rank, size);
      EXPECT_EQ(block.num_nodes, whole.num_nodes());
      EXPECT_EQ(block.num_tets, whole.num_tets());
      EXPECT_EQ(block.num_triangles, whole.num_triangles());
      EXPECT_EQ(block.first_triangle, next_triangle);
      next_triangle += block.triangles.cols();
      nodes.conservativeResize(3, nodes.cols() + block.nodes.cols());
      nodes.rightCols(block.nodes.cols()) = block.nodes;
      tets.conservativeResize(4, tets.cols() + block.tets.cols());
      tets.rightCols(block.tets.cols()) = block.tets;
      for (Index t = 0; t < block.triangles.cols(); ++t)
        got.insert(Named(block.triangles, t, block.first_triangle, block.groups));
      ASSERT_EQ(block.groups.back().name, "volume");
      volume += static_cast<std::int64_t>(block.groups.back().items.size());
    }
    EXPECT_EQ(nodes, whole.nodes);
    EXPECT_EQ(tets, whole.tets);
    EXPECT_EQ(next_triangle, whole.num_triangles());
    EXPECT_EQ(got, expected);
    EXPECT_EQ(volume, whole.num_tets());
  }
}

// A whole mesh's blocks slice its nodes, tets, triangles and group items by rank.
TEST(TetBoxBlock, AWholeMeshSlicesIntoBlocks) {
  const Mesh whole = MakeTetBox(Vec3::Zero(), Vec3::Ones(), {3, 2, 2});
  const MeshBlock block = BlockOfMesh(whole, 1, 3);
  const Index n0 = whole.num_nodes() / 3, e0 = whole.num_tets() / 3;
  EXPECT_EQ(block.nodes, whole.nodes.middleCols(n0, 2 * whole.num_nodes() / 3 - n0));
  EXPECT_EQ(block.tets, whole.tets.middleCols(e0, 2 * whole.num_tets() / 3 - e0));
  EXPECT_EQ(block.first_triangle, whole.num_triangles() / 3);
  for (const MeshGroup& g : block.groups)
    for (int item : g.items) {
      const Index count = g.dim == 0   ? whole.num_nodes()
                          : g.dim == 2 ? whole.num_triangles()
                                       : whole.num_tets();
      EXPECT_GE(item, count / 3);
      EXPECT_LT(item, 2 * count / 3);
    }
}

}  // namespace
}  // namespace gipsi
