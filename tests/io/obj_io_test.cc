#include "gipsi/io/obj_io.h"

#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "io/io_test_util.h"

namespace gipsi {
namespace {

using test::InputErrorMessage;
using test::Scratch;
using test::WriteBytes;
using ::testing::HasSubstr;

TEST(ObjReader, ReadsCubeWithAllIndexFormsAndNegativeIndices) {
  Mesh mesh = ReadObj(test::MeshData("cube_surface.obj"));
  EXPECT_EQ(mesh.num_nodes(), 8);
  ASSERT_EQ(mesh.num_triangles(), 12);
  EXPECT_EQ(mesh.triangles.col(0), Eigen::Vector3i(0, 3, 2));  // quad 1 4 3 2, fanned
  EXPECT_EQ(mesh.triangles.col(1), Eigen::Vector3i(0, 2, 1));
  EXPECT_EQ(mesh.triangles.col(2), Eigen::Vector3i(4, 5, 6));  // 5/1 6/1 7/1 8/1
  EXPECT_EQ(mesh.triangles.col(8), Eigen::Vector3i(2, 3, 7));  // -6 -5 -1 -2
  EXPECT_EQ(mesh.triangles.col(9), Eigen::Vector3i(2, 7, 6));
}

TEST(ObjReader, ReadsLiverSamplesWithExpectedCounts) {
  Mesh coarse = ReadObj(test::SharedData("liver/liver.obj"));
  EXPECT_EQ(coarse.num_nodes(), 181);
  EXPECT_EQ(coarse.num_triangles(), 274);
  Mesh smooth = ReadObj(test::SharedData("liver/liver-smooth.obj"));
  EXPECT_EQ(smooth.num_nodes(), 2194);
  EXPECT_EQ(smooth.num_triangles(), 4384);
}

TEST(ObjReader, ReportsOutOfRangeIndexWithFileAndLine) {
  auto path = WriteBytes(Scratch("range.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 3\nf 1 2 4\n");
  EXPECT_EQ(InputErrorMessage([&] { ReadObj(path); }),
            path.string() + ": line 6: vertex index 4 out of range: the file has 3 vertices");
}

TEST(ObjReader, RejectsIndexZeroAndBadNumbers) {
  auto zero = WriteBytes(Scratch("zero.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  EXPECT_THAT(InputErrorMessage([&] { ReadObj(zero); }),
              HasSubstr("line 4: vertex index 0 is invalid"));
  auto bad = WriteBytes(Scratch("bad.obj"), "v 0 0 0\nv 1 zero 0\n");
  EXPECT_THAT(InputErrorMessage([&] { ReadObj(bad); }),
              HasSubstr("line 2: expected a y coordinate (a finite number), got 'zero'"));
  auto before = WriteBytes(Scratch("before.obj"), "v 0 0 0\nf -1 -2 -3\n");
  EXPECT_THAT(InputErrorMessage([&] { ReadObj(before); }),
              HasSubstr("line 2: relative vertex index -2 points before the first vertex"));
}

TEST(ObjReader, RejectsDegenerateFace) {
  auto path = WriteBytes(Scratch("degenerate.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1\n");
  EXPECT_THAT(InputErrorMessage([&] { ReadObj(path); }),
              HasSubstr("line 4: face repeats vertex 1"));
}

TEST(ObjWriter, RoundTripsExactly) {
  Mesh mesh = ReadObj(test::SharedData("liver/liver-smooth.obj"));
  mesh.nodes *= 1.0 / 3.0;  // coordinates that need all 17 digits
  auto path = Scratch("liver.obj");
  WriteObj(path, mesh.nodes, mesh.triangles);
  Mesh back = ReadObj(path);
  EXPECT_EQ(back.nodes, mesh.nodes);
  EXPECT_EQ(back.triangles, mesh.triangles);
}

TEST(ObjReader, RejectsMissingFile) {
  EXPECT_EQ(InputErrorMessage([] { ReadObj("/nonexistent/x.obj"); }),
            "/nonexistent/x.obj: cannot open mesh file for reading: No such file or directory");
}

}  // namespace
}  // namespace gipsi
