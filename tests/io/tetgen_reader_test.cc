#include "gipsi/io/tetgen_reader.h"

#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "io/io_test_util.h"

namespace gipsi {
namespace {

using test::InputErrorMessage;
using test::Scratch;
using test::WriteBytes;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

void ExpectTwoTets(const Mesh& mesh) {
  ASSERT_EQ(mesh.num_nodes(), 5);
  ASSERT_EQ(mesh.num_tets(), 2);
  ASSERT_EQ(mesh.num_triangles(), 2);
  EXPECT_EQ(mesh.nodes.col(4), Vec3(1, 1, 1));
  EXPECT_EQ(mesh.tets.col(1), Eigen::Vector4i(1, 2, 3, 4));
  EXPECT_EQ(mesh.triangles.col(0), Eigen::Vector3i(0, 2, 1));
}

TEST(TetGenReader, ReadsNodeEleFaceWithRegionsAndMarkers) {
  Mesh mesh = ReadTetGen(test::MeshData("two_tets.node"));
  ExpectTwoTets(mesh);
  ASSERT_EQ(mesh.groups.size(), 4u);
  EXPECT_EQ(mesh.FindGroup("region_1")->dim, 3);
  EXPECT_THAT(mesh.FindGroup("region_1")->items, ElementsAre(0));
  EXPECT_THAT(mesh.FindGroup("region_2")->items, ElementsAre(1));
  EXPECT_EQ(mesh.FindGroup("marker_5")->dim, 2);
  EXPECT_THAT(mesh.FindGroup("marker_5")->items, ElementsAre(0));
  EXPECT_THAT(mesh.FindGroup("marker_6")->items, ElementsAre(1));
}

TEST(TetGenReader, AcceptsTheEleOrFacePath) {
  ExpectTwoTets(ReadTetGen(test::MeshData("two_tets.ele")));
  ExpectTwoTets(ReadTetGen(test::MeshData("two_tets.face")));
}

TEST(TetGenReader, ReadsZeroBasedNumberingWithoutFaceFile) {
  WriteBytes(Scratch("zero.node"), "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n");
  WriteBytes(Scratch("zero.ele"), "2 4 0\n0 0 1 2 3\n1 1 2 3 4\n");
  Mesh mesh = ReadTetGen(Scratch("zero.node"));
  EXPECT_EQ(mesh.num_nodes(), 5);
  EXPECT_EQ(mesh.tets.col(0), Eigen::Vector4i(0, 1, 2, 3));
  EXPECT_EQ(mesh.num_triangles(), 0);
  EXPECT_TRUE(mesh.groups.empty());
}

TEST(TetGenReader, ReadsSecondOrderTetsAsCornersAndFractionalRegions) {
  WriteBytes(Scratch("q.node"), "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n");
  WriteBytes(Scratch("q.ele"), "1 10 1\n1 1 2 3 4 1 1 1 1 1 1 0.5\n");
  Mesh mesh = ReadTetGen(Scratch("q.ele"));
  EXPECT_EQ(mesh.tets.col(0), Eigen::Vector4i(0, 1, 2, 3));
  EXPECT_NE(mesh.FindGroup("region_0.5"), nullptr);
}

TEST(TetGenReader, ReportsUndefinedNodeWithFileAndLine) {
  WriteBytes(Scratch("bad.node"), "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n");
  auto ele = WriteBytes(Scratch("bad.ele"), "# tets\n1 4 0\n\n1 1 2 3 5\n");
  EXPECT_EQ(InputErrorMessage([&] { ReadTetGen(ele); }),
            ele.string() + ": line 4: refers to undefined node 5");
}

TEST(TetGenReader, ReportsShortLineWithFileAndLine) {
  auto node = WriteBytes(Scratch("short.node"), "2 3 0 1\n1 0 0 0 1\n2 1 0 0\n");
  EXPECT_EQ(InputErrorMessage([&] { ReadTetGen(node); }),
            node.string() +
                ": line 3: expected a point line '<#> <x> <y> <z> [attributes] [marker]' with 5 "
                "values, got 4");
}

TEST(TetGenReader, RejectsMissingEleFile) {
  auto node = WriteBytes(Scratch("alone.node"), "1 3 0 0\n1 0 0 0\n");
  EXPECT_THAT(InputErrorMessage([&] { ReadTetGen(node); }),
              HasSubstr("alone.ele: cannot open mesh file for reading: No such file or directory"));
}

}  // namespace
}  // namespace gipsi
