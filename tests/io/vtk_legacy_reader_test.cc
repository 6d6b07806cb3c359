#include "gipsi/io/vtk_legacy_reader.h"

#include <cstdint>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "io/io_test_util.h"

namespace gipsi {
namespace {

using test::CountRejectedPrefixes;
using test::ExpectTwoTetsAndTriangle;
using test::InputErrorMessage;
using test::MeshData;
using test::Put;
using test::Scratch;
using test::WriteBytes;
using ::testing::HasSubstr;

const bool kSwap = test::LittleEndianHost();  // legacy VTK binary is big-endian

/// Two tets and a triangle as a BINARY unstructured grid, classic or VTK 5.1 cell layout.
std::string TwoTetsBinary(bool layout51) {
  std::string s = "# vtk DataFile Version 3.0\nbinary\nBINARY\nDATASET UNSTRUCTURED_GRID\n";
  s += "POINTS 5 double\n";
  for (double c : {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1}) Put(s, c, kSwap);
  if (layout51) {
    s += "\nCELLS 4 11\nOFFSETS vtktypeint64\n";
    for (std::int64_t v : {0, 4, 8, 11}) Put(s, v, kSwap);
    s += "\nCONNECTIVITY vtktypeint64\n";
    for (std::int64_t v : {0, 1, 2, 3, 1, 2, 3, 4, 0, 1, 2}) Put(s, v, kSwap);
  } else {
    s += "\nCELLS 3 14\n";
    for (std::int32_t v : {4, 0, 1, 2, 3, 4, 1, 2, 3, 4, 3, 0, 1, 2}) Put(s, v, kSwap);
  }
  s += "\nCELL_TYPES 3\n";
  for (std::int32_t v : {10, 10, 5}) Put(s, v, kSwap);
  s += "\nCELL_DATA 3\nSCALARS id int 1\nLOOKUP_TABLE default\n";
  for (std::int32_t v : {0, 1, 2}) Put(s, v, kSwap);
  s += "\n";
  return s;
}

TEST(VtkLegacyReader, ReadsAsciiGridKeepingTetsAndTrianglesOnly) {
  ExpectTwoTetsAndTriangle(ReadVtkLegacy(MeshData("two_tets_ascii.vtk")));  // drops the line
}

TEST(VtkLegacyReader, ReadsVtk51OffsetsConnectivityLayoutAndSkipsMetadata) {
  ExpectTwoTetsAndTriangle(ReadVtkLegacy(MeshData("two_tets_v51.vtk")));
}

TEST(VtkLegacyReader, ReadsBinaryBigEndianGrid) {
  ExpectTwoTetsAndTriangle(ReadVtkLegacy(WriteBytes(Scratch("b.vtk"), TwoTetsBinary(false))));
}

TEST(VtkLegacyReader, ReadsBinaryVtk51Layout) {
  ExpectTwoTetsAndTriangle(ReadVtkLegacy(WriteBytes(Scratch("b51.vtk"), TwoTetsBinary(true))));
}

TEST(VtkLegacyReader, SplitsPolygonsIntoTriangleFans) {
  Mesh mesh = ReadVtkLegacy(MeshData("cube_quads.vtk"));
  EXPECT_EQ(mesh.num_nodes(), 8);
  EXPECT_EQ(mesh.num_triangles(), 12);
  EXPECT_EQ(mesh.triangles.col(0), Eigen::Vector3i(0, 3, 2));
  EXPECT_EQ(mesh.triangles.col(1), Eigen::Vector3i(0, 2, 1));
}

TEST(VtkLegacyReader, SplitsTriangleStripsKeepingOrientation) {
  std::string s =
      "# vtk DataFile Version 3.0\nstrip\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n"
      "0 0 0 1 0 0 0 1 0 1 1 0\nTRIANGLE_STRIPS 1 5\n4 0 1 2 3\n";
  Mesh mesh = ReadVtkLegacy(WriteBytes(Scratch("strip.vtk"), s));
  ASSERT_EQ(mesh.num_triangles(), 2);
  EXPECT_EQ(mesh.triangles.col(0), Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(mesh.triangles.col(1), Eigen::Vector3i(2, 1, 3));
}

TEST(VtkLegacyReader, ReadsLiverBinaryPolydataSample) {
  Mesh mesh = ReadVtkLegacy(test::SharedData("liver/liver.vtk"));
  EXPECT_EQ(mesh.num_nodes(), 5008);
  EXPECT_EQ(mesh.num_triangles(), 10000);
  EXPECT_EQ(mesh.num_tets(), 0);
}

TEST(VtkLegacyReader, RejectsBrokenLiverSampleNamingTheFile) {
  auto path = test::SharedData("liver/liver_for_test_broken.vtk");
  std::string message = InputErrorMessage([&] { ReadVtkLegacy(path); });
  EXPECT_THAT(message, HasSubstr(path.string() + ": line "));
  EXPECT_THAT(message, HasSubstr("expected a section keyword"));
}

TEST(VtkLegacyReader, RejectsCountLargerThanFileBeforeAllocating) {
  std::string s = TwoTetsBinary(false);
  s.replace(s.find("POINTS 5"), 8, "POINTS 2000000000");
  std::string message = InputErrorMessage([&] { ReadVtkLegacy(WriteBytes(Scratch("c.vtk"), s)); });
  EXPECT_THAT(message, HasSubstr("line 5: declares 2000000000 points, but only"));
}

TEST(VtkLegacyReader, RejectsCellCountLargerThanItsArrayBeforeAllocating) {
  // A fuzzer finding: a cell count of 2e16 with a one-value array used to size an allocation.
  std::string s = test::ReadBytes(MeshData("two_tets_ascii.vtk"));
  s.replace(s.find("CELLS 4 17"), 10, "CELLS 20000000000000000 17");
  auto path = WriteBytes(Scratch("cells.vtk"), s);
  EXPECT_EQ(InputErrorMessage([&] { ReadVtkLegacy(path); }),
            path.string() +
                ": line 8 (CELLS): expected at most 17 cells in 17 values, got a count of "
                "20000000000000000");
}

TEST(VtkLegacyReader, RejectsOutOfRangePointIndexNamingLineAndSection) {
  std::string s = test::ReadBytes(MeshData("two_tets_ascii.vtk"));
  s.replace(s.find("4 1 2 3 4"), 9, "4 1 2 3 7");
  auto path = WriteBytes(Scratch("range.vtk"), s);
  EXPECT_EQ(InputErrorMessage([&] { ReadVtkLegacy(path); }),
            path.string() + ": line 8 (CELLS): cell 1 refers to point 7, out of range [0, 5)");
}

TEST(VtkLegacyReader, RejectsCellWhosePointCountDoesNotMatchItsType) {
  std::string s = test::ReadBytes(MeshData("two_tets_ascii.vtk"));
  s.replace(s.find("10\n10\n5"), 7, "10\n5\n10");
  EXPECT_THAT(InputErrorMessage([&] { ReadVtkLegacy(WriteBytes(Scratch("t.vtk"), s)); }),
              HasSubstr("expected 3 point indices for a triangle (cell 1), got 4"));
}

TEST(VtkLegacyReader, RejectsMalformedNumberWithLine) {
  std::string s = test::ReadBytes(MeshData("two_tets_ascii.vtk"));
  s.replace(s.find("1 1 1"), 5, "1 1 x");
  EXPECT_THAT(InputErrorMessage([&] { ReadVtkLegacy(WriteBytes(Scratch("n.vtk"), s)); }),
              HasSubstr("line 7: expected a point coordinate (a finite number), got 'x'"));
}

TEST(VtkLegacyReader, RejectsUnsupportedDataset) {
  std::string s = "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\n";
  EXPECT_THAT(InputErrorMessage([&] { ReadVtkLegacy(WriteBytes(Scratch("s.vtk"), s)); }),
              HasSubstr("line 4: unsupported dataset 'STRUCTURED_POINTS'"));
}

TEST(VtkLegacyReader, SurvivesEveryTruncationOfBinary) {
  const std::string bytes = TwoTetsBinary(true);
  const std::size_t rejected = CountRejectedPrefixes(
      bytes, Scratch("cut.vtk"), [](const auto& p) { return ReadVtkLegacy(p); });
  // Only cuts inside the trailing data the reader ignores give a mesh (the whole one, checked
  // above); every cut before the connectivity ends is rejected.
  EXPECT_GE(rejected, bytes.size() * 8 / 10);
}

TEST(VtkLegacyReader, RejectsMissingFile) {
  EXPECT_EQ(InputErrorMessage([] { ReadVtkLegacy("/nonexistent/x.vtk"); }),
            "/nonexistent/x.vtk: cannot open mesh file for reading: No such file or directory");
}

}  // namespace
}  // namespace gipsi
