#include "gipsi/geometry/boundary.h"

#include <map>
#include <utility>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gipsi/base/error.h"
#include "gipsi/geometry/generators.h"

namespace gipsi {
namespace {

using ::testing::ElementsAre;
using ::testing::StrEq;
using ::testing::ThrowsMessage;

/// Volume enclosed by a closed triangle surface (divergence theorem): Σ a·(b×c)/6. Positive
/// exactly when the triangles are oriented outward.
double EnclosedVolume(const Points& x, const Triangles& tri) {
  double volume = 0;
  for (Index t = 0; t < tri.cols(); ++t)
    volume += x.col(tri(0, t)).dot(x.col(tri(1, t)).cross(x.col(tri(2, t)))) / 6;
  return volume;
}

TEST(TetBoundary, BoxOfTwoByTwoByTwoCellsHas48Triangles) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2});
  const BoundarySurface boundary = ExtractTetBoundary(box.nodes, box.tets);
  // 6 faces × (2·2 quads) × 2 triangles.
  EXPECT_EQ(boundary.num_triangles(), 48);
  EXPECT_EQ(boundary.face_to_tet.size(), 48u);
}

TEST(TetBoundary, BoxBoundaryIsClosedAndConsistentlyOriented) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 2, 3), {3, 2, 2});
  const BoundarySurface boundary = ExtractTetBoundary(box.nodes, box.tets);
  // Every directed edge appears once and its reverse once: closed, consistently oriented.
  std::map<std::pair<int, int>, int> directed;
  for (Index t = 0; t < boundary.num_triangles(); ++t)
    for (int a = 0; a < 3; ++a)
      ++directed[{boundary.triangles(a, t), boundary.triangles((a + 1) % 3, t)}];
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u);
  }
}

TEST(TetBoundary, BoxBoundaryIsOrientedOutward) {
  const Vec3 lo(-1, 0.5, 2), hi(2, 1.5, 4);
  const Mesh box = MakeTetBox(lo, hi, {3, 2, 4});
  const BoundarySurface boundary = ExtractTetBoundary(box.nodes, box.tets);
  Points x;
  boundary.Gather(box.nodes, x);
  EXPECT_NEAR(EnclosedVolume(x, boundary.triangles), (hi - lo).prod(), 1e-12);
}

TEST(TetBoundary, FacesOfANegativelyOrientedTetPointOutward) {
  Points nodes(3, 4);
  nodes << 0, 1, 0, 0,  //
      0, 0, 1, 0,       //
      0, 0, 0, 1;
  Tets tets(4, 1);
  tets << 0, 2, 1, 3;  // negative order
  const BoundarySurface boundary = ExtractTetBoundary(nodes, tets);
  ASSERT_EQ(boundary.num_triangles(), 4);
  EXPECT_NEAR(EnclosedVolume(nodes, boundary.triangles), 1.0 / 6, 1e-15);
  EXPECT_THAT(boundary.face_to_tet, ElementsAre(0, 0, 0, 0));
}

TEST(TetBoundary, VerticesAreTheBoundaryNodesInIncreasingOrder) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {3, 3, 3});
  const BoundarySurface boundary = ExtractTetBoundary(box.nodes, box.tets);
  // 4³ nodes minus the 2³ interior ones.
  ASSERT_EQ(boundary.num_vertices(), 64 - 8);
  for (std::size_t v = 0; v < boundary.vertex_to_node.size(); ++v) {
    if (v > 0) {
      EXPECT_LT(boundary.vertex_to_node[v - 1], boundary.vertex_to_node[v]);
    }
    const Vec3 x = box.nodes.col(boundary.vertex_to_node[v]);
    EXPECT_TRUE((x.array() == 0).any() || (x.array() == 1).any());
  }
  // Each boundary triangle is a face of the tet it names.
  for (Index t = 0; t < boundary.num_triangles(); ++t) {
    const auto tet = box.tets.col(boundary.face_to_tet[std::size_t(t)]);
    for (int a = 0; a < 3; ++a) {
      const int node = boundary.vertex_to_node[std::size_t(boundary.triangles(a, t))];
      EXPECT_TRUE((tet.array() == node).any());
    }
  }
}

TEST(MakeBoundary, UsesTheTrianglesOfASurfaceMeshWithTheirNodes) {
  Mesh sheet = MakeTriangleSheet(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), {2, 1});
  // An extra node no triangle uses, placed first: vertices skip it.
  Points nodes(3, sheet.num_nodes() + 1);
  nodes << Vec3(5, 5, 5), sheet.nodes;
  sheet.nodes = nodes;
  sheet.triangles.array() += 1;
  const BoundarySurface boundary = MakeBoundary(sheet);
  EXPECT_EQ(boundary.num_triangles(), 4);
  EXPECT_THAT(boundary.vertex_to_node, ElementsAre(1, 2, 3, 4, 5, 6));
  EXPECT_THAT(boundary.face_to_tet, ElementsAre(-1, -1, -1, -1));
  for (Index t = 0; t < 4; ++t)
    for (int a = 0; a < 3; ++a)
      EXPECT_EQ(boundary.vertex_to_node[std::size_t(boundary.triangles(a, t))],
                sheet.triangles(a, t));
}

TEST(MakeBoundary, UsesTetsWhenPresent) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 1, 1});
  const BoundarySurface boundary = MakeBoundary(box);
  EXPECT_EQ(boundary.num_triangles(), 12);
  for (int tet : boundary.face_to_tet) EXPECT_GE(tet, 0);
}

TEST(MakeBoundary, RejectsAMeshWithoutElements) {
  Mesh mesh;
  mesh.nodes = Points::Zero(3, 3);
  EXPECT_THAT([&] { MakeBoundary(mesh); },
              ThrowsMessage<InputError>(StrEq("mesh: has neither tetrahedra nor triangles (3 "
                                              "nodes); a boundary surface needs one of them")));
}

TEST(BoundarySurface, GatherCopiesBoundaryVertexPositionsWithoutReallocating) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2});
  const BoundarySurface boundary = MakeBoundary(box);
  Points out(3, boundary.num_vertices());
  const double* storage = out.data();
  boundary.Gather(box.nodes, out);
  EXPECT_EQ(out.data(), storage);
  for (Index v = 0; v < boundary.num_vertices(); ++v)
    EXPECT_EQ(out.col(v), box.nodes.col(boundary.vertex_to_node[std::size_t(v)]));
}

}  // namespace
}  // namespace gipsi
