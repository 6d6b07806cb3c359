#include "gipsi/io/stl_io.h"

#include <cstdint>
#include <map>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/io/obj_io.h"
#include "io/io_test_util.h"

namespace gipsi {
namespace {

using test::InputErrorMessage;
using test::Put;
using test::Scratch;
using test::WriteBytes;
using ::testing::HasSubstr;

/// Expects `b` to be `a` up to a renumbering of vertices (by position, within `tol`) that
/// maps triangles to the same triangles.
void ExpectSameSurface(const Mesh& a, const Mesh& b, double tol) {
  ASSERT_EQ(a.num_nodes(), b.num_nodes());
  ASSERT_EQ(a.num_triangles(), b.num_triangles());
  std::vector<int> b_of_a(std::size_t(a.num_nodes()), -1);
  for (Index t = 0; t < a.num_triangles(); ++t) {
    for (Index k = 0; k < 3; ++k) {
      int va = a.triangles(k, t), vb = b.triangles(k, t);
      EXPECT_LE((a.nodes.col(va) - b.nodes.col(vb)).cwiseAbs().maxCoeff(), tol);
      if (b_of_a[std::size_t(va)] < 0) b_of_a[std::size_t(va)] = vb;
      EXPECT_EQ(b_of_a[std::size_t(va)], vb) << "vertex " << va << " split";
    }
  }
}

TEST(StlReader, ReadsAsciiCubeWeldedToEightVertices) {
  Mesh mesh = ReadStl(test::MeshData("cube_ascii.stl"));
  EXPECT_EQ(mesh.num_nodes(), 8);
  EXPECT_EQ(mesh.num_triangles(), 12);
  Mesh obj = ReadObj(test::MeshData("cube_surface.obj"));
  EXPECT_EQ(mesh.nodes.rowwise().sum(), obj.nodes.rowwise().sum());
}

TEST(StlWriter, BinaryRoundTripWeldsBackToOriginalVertexCount) {
  Mesh mesh = ReadObj(test::SharedData("liver/liver.obj"));
  mesh.RemoveUnusedNodes();  // liver.obj has 42 vertices no face uses; STL cannot keep them
  ASSERT_EQ(mesh.num_nodes(), 139);
  auto path = Scratch("liver.stl");
  WriteStl(path, mesh.nodes, mesh.triangles);
  EXPECT_EQ(std::filesystem::file_size(path), 84u + 50u * 274u);
  Mesh back = ReadStl(path);
  EXPECT_EQ(back.num_nodes(), 139);
  ExpectSameSurface(mesh, back, 1e-6);  // float32 storage
}

TEST(StlWriter, AsciiRoundTripIsExact) {
  Mesh mesh = ReadObj(test::SharedData("liver/liver-smooth.obj"));
  auto path = Scratch("liver.stl");
  WriteStl(path, mesh.nodes, mesh.triangles, StlFormat::kAscii);
  Mesh back = ReadStl(path);
  EXPECT_EQ(back.num_nodes(), 2194);
  ExpectSameSurface(mesh, back, 0.0);
}

TEST(StlReader, WeldsCornersWithinToleranceOnly) {
  std::string text = test::ReadBytes(test::MeshData("cube_ascii.stl"));
  // Move one corner of one facet by 1e-12 (relative 6e-13 of the diagonal).
  text.replace(text.find("vertex 1 1 1"), 12, "vertex 1 1 1.000000000001");
  auto path = WriteBytes(Scratch("cube.stl"), text);
  EXPECT_EQ(ReadStl(path).num_nodes(), 8);
  EXPECT_EQ(ReadStl(path, {.weld_tolerance = 0.0}).num_nodes(), 9);
  // A large tolerance collapses triangles, which are dropped.
  Mesh collapsed = ReadStl(path, {.weld_tolerance = 10.0});
  EXPECT_EQ(collapsed.num_nodes(), 1);
  EXPECT_EQ(collapsed.num_triangles(), 0);
}

TEST(StlReader, DetectsBinaryWhoseHeaderStartsWithSolid) {
  std::string s = "solid but actually binary";
  s.resize(80, '\0');
  Put<std::uint32_t>(s, 1);
  for (float v : {0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) Put(s, v);
  s.append(2, '\0');
  Mesh mesh = ReadStl(WriteBytes(Scratch("solid.stl"), s));
  EXPECT_EQ(mesh.num_nodes(), 3);
  EXPECT_EQ(mesh.num_triangles(), 1);
}

TEST(StlReader, RejectsTruncatedBinary) {
  std::string s(80, ' ');
  Put<std::uint32_t>(s, 100);
  s.append(50 * 3, '\0');
  auto path = WriteBytes(Scratch("short.stl"), s);
  EXPECT_EQ(InputErrorMessage([&] { ReadStl(path); }),
            path.string() +
                ": byte offset 80: binary STL declares 100 triangles, which needs 5084 bytes, but "
                "the file has 234 bytes (truncated file?)");
}

TEST(StlReader, RejectsNonFiniteBinaryCoordinate) {
  std::string s(80, ' ');
  Put<std::uint32_t>(s, 1);
  for (float v : {0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, NAN, 0.f}) Put(s, v);
  s.append(2, '\0');
  EXPECT_THAT(InputErrorMessage([&] { ReadStl(WriteBytes(Scratch("nan.stl"), s)); }),
              HasSubstr("byte offset 124: triangle 0 has a non-finite vertex coordinate"));
}

TEST(StlReader, ReportsLineOfMalformedAscii) {
  std::string text = test::ReadBytes(test::MeshData("cube_ascii.stl"));
  text.replace(text.find("endloop"), 7, "endlop");
  auto path = WriteBytes(Scratch("bad.stl"), text);
  EXPECT_EQ(InputErrorMessage([&] { ReadStl(path); }),
            path.string() + ": line 7: expected 'endloop', got 'endlop'");
}

TEST(StlReader, RejectsMissingFile) {
  EXPECT_EQ(InputErrorMessage([] { ReadStl("/nonexistent/x.stl"); }),
            "/nonexistent/x.stl: cannot open mesh file for reading: No such file or directory");
}

}  // namespace
}  // namespace gipsi
