#include "gipsi/geometry/region.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gipsi/base/error.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/normals.h"

namespace gipsi {
namespace {

using ::testing::ElementsAre;
using ::testing::SizeIs;
using ::testing::StrEq;
using ::testing::ThrowsMessage;

/// [0,1]³ in 2×2×2 cells: 27 nodes on the lattice {0, 0.5, 1}³.
Mesh UnitBox() { return MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2}); }

TEST(SelectNodes, AllSelectsEveryNode) {
  EXPECT_THAT(SelectNodes(AllRegion{}, UnitBox()), SizeIs(27));
}

TEST(SelectNodes, BoxIsInclusiveWithARelativeTolerance) {
  const Mesh box = UnitBox();
  // The face z = 0, with the box's upper corner a hair inside the nodes at x = y = 1.
  const auto face = SelectNodes(BoxRegion{Vec3(0, 0, 0), Vec3(1 - 1e-12, 1 - 1e-12, 0)}, box);
  EXPECT_THAT(face, SizeIs(9));
  for (int n : face) EXPECT_EQ(box.nodes(2, n), 0);
  // A corner region holding one node only; a tolerance of 1e-9 of the diagonal does not reach
  // the next layer.
  EXPECT_THAT(SelectNodes(BoxRegion{Vec3(-1, -1, -1), Vec3(0.4, 0.4, 0.4)}, box), ElementsAre(0));
}

TEST(SelectNodes, HalfSpaceKeepsTheSideTheNormalPointsTo) {
  const Mesh box = UnitBox();
  EXPECT_THAT(SelectNodes(HalfSpaceRegion{Vec3(0.5, 0, 0), Vec3(2, 0, 0)}, box), SizeIs(18));
  EXPECT_THAT(SelectNodes(HalfSpaceRegion{Vec3(0.5, 0, 0), Vec3(-1, 0, 0)}, box), SizeIs(18));
  EXPECT_THAT(SelectNodes(HalfSpaceRegion{Vec3(0.75, 0, 0), Vec3(1, 0, 0)}, box), SizeIs(9));
}

TEST(SelectNodes, SphereIncludesItsSurface) {
  // The origin and its three neighbours at distance 0.5.
  EXPECT_THAT(SelectNodes(SphereRegion{Vec3(0, 0, 0), 0.5}, UnitBox()), ElementsAre(0, 1, 3, 9));
}

TEST(SelectNodes, GroupSelectsTheNodesOfItsElements) {
  const Mesh box = UnitBox();
  const auto xmin = SelectNodes(GroupRegion{"xmin"}, box);
  EXPECT_THAT(xmin, SizeIs(9));
  for (int n : xmin) EXPECT_EQ(box.nodes(0, n), 0);
  EXPECT_THAT(SelectNodes(GroupRegion{"volume"}, box), SizeIs(27));
  const Mesh sheet = MakeTriangleSheet(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), {3, 2});
  EXPECT_THAT(SelectNodes(GroupRegion{"u1"}, sheet), ElementsAre(3, 7, 11));
}

TEST(SelectNodes, UnknownGroupListsTheAvailableOnes) {
  EXPECT_THAT([] { SelectNodes(GroupRegion{"apex"}, UnitBox()); },
              ThrowsMessage<InputError>(
                  StrEq("group region 'apex': no mesh group of that name; available groups: "
                        "'xmin', 'xmax', 'ymin', 'ymax', 'zmin', 'zmax', 'volume'")));
  Mesh bare;
  bare.nodes = Points::Zero(3, 1);
  EXPECT_THAT([&] { SelectNodes(GroupRegion{"apex"}, bare); },
              ThrowsMessage<InputError>(StrEq(
                  "group region 'apex': no mesh group of that name; available groups: (none)")));
}

TEST(SelectNodes, NodeIdsAreSortedUniqueAndRangeChecked) {
  EXPECT_THAT(SelectNodes(NodeIdsRegion{{5, 2, 5, 0}}, UnitBox()), ElementsAre(0, 2, 5));
  EXPECT_THAT(
      [] {
        SelectNodes(NodeIdsRegion{{3, 27}}, UnitBox());
      },
      ThrowsMessage<InputError>(StrEq("node id region: ids[1]: node id 27 out of range [0, 27)")));
}

TEST(SelectNodes, RejectsAZeroHalfSpaceNormalAndANegativeRadius) {
  EXPECT_THAT(
      [] {
        SelectNodes(HalfSpaceRegion{Vec3(0, 0, 0), Vec3(0, 0, 0)}, UnitBox());
      },
      ThrowsMessage<InputError>(
          StrEq("half-space region: normal must be a finite non-zero vector")));
  EXPECT_THAT(
      [] {
        SelectNodes(SphereRegion{Vec3(0, 0, 0), -1}, UnitBox());
      },
      ThrowsMessage<InputError>(StrEq("sphere region: radius must be non-negative, got -1")));
}

TEST(SelectBoundaryVertices, MapsSelectedNodesToBoundaryVertices) {
  const Mesh box = UnitBox();
  const BoundarySurface boundary = MakeBoundary(box);
  // All nodes but the centre (node 13) are on the boundary.
  EXPECT_THAT(SelectBoundaryVertices(AllRegion{}, box, boundary), SizeIs(26));
  EXPECT_THAT(SelectBoundaryVertices(NodeIdsRegion{{13}}, box, boundary), SizeIs(0));
  const auto xmax = SelectBoundaryVertices(GroupRegion{"xmax"}, box, boundary);
  ASSERT_THAT(xmax, SizeIs(9));
  for (int v : xmax) EXPECT_EQ(box.nodes(0, boundary.vertex_to_node[std::size_t(v)]), 1);
}

TEST(SelectBoundaryFaces, TriangleGroupMatchesBoundaryTrianglesByNodes) {
  const Mesh box = UnitBox();
  const BoundarySurface boundary = MakeBoundary(box);
  Points x;
  boundary.Gather(box.nodes, x);
  const Points normals = FaceNormals(x, boundary.triangles);
  const auto ymin = SelectBoundaryFaces(GroupRegion{"ymin"}, box, boundary);
  ASSERT_THAT(ymin, SizeIs(8));
  for (int t : ymin) EXPECT_EQ(normals.col(t), Vec3(0, -1, 0));
}

TEST(SelectBoundaryFaces, GeometricRegionSelectsFacesWithAllVerticesInside) {
  const Mesh box = UnitBox();
  const BoundarySurface boundary = MakeBoundary(box);
  EXPECT_THAT(SelectBoundaryFaces(AllRegion{}, box, boundary), SizeIs(48));
  // z >= 0.75: the 8 triangles of the top face. z >= 0.5: also the side triangles of the upper
  // row of quads (4 sides × 2 quads × 2 triangles).
  EXPECT_THAT(SelectBoundaryFaces(HalfSpaceRegion{Vec3(0, 0, 0.75), Vec3(0, 0, 1)}, box, boundary),
              SizeIs(8));
  EXPECT_THAT(SelectBoundaryFaces(HalfSpaceRegion{Vec3(0, 0, 0.5), Vec3(0, 0, 1)}, box, boundary),
              SizeIs(8 + 4 * 2 * 2));
  // A node group selects faces by their vertices too: the centre node alone selects nothing.
  EXPECT_THAT(SelectBoundaryFaces(NodeIdsRegion{{13}}, box, boundary), SizeIs(0));
}

}  // namespace
}  // namespace gipsi
