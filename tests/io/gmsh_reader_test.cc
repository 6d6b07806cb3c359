#include "gipsi/io/gmsh_reader.h"

#include <cstdint>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "io/io_test_util.h"

namespace gipsi {
namespace {

using test::CountRejectedPrefixes;
using test::InputErrorMessage;
using test::MeshData;
using test::Put;
using test::Scratch;
using test::WriteBytes;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

/// The two-tet mesh of two_tets_v41.msh in Gmsh 4.1 binary, written byte by byte. The surface
/// node block is parametric (u, v follow x, y, z). `swap` writes the other byte order.
std::string TwoTets41Binary(bool swap) {
  std::string s = "$MeshFormat\n4.1 1 8\n";
  auto i32 = [&](std::int32_t v) { Put(s, v, swap); };
  auto size = [&](std::uint64_t v) { Put(s, v, swap); };
  auto real = [&](double v) { Put(s, v, swap); };
  auto node = [&](double x, double y, double z) { real(x), real(y), real(z); };
  i32(1);
  s += "\n$EndMeshFormat\n$PhysicalNames\n2\n2 2 \"bottom\"\n3 1 \"liver\"\n$EndPhysicalNames\n";
  s += "$Entities\n";
  size(1), size(0), size(1), size(1);
  i32(7), node(1, 1, 1), size(0);                                          // point 7
  i32(3), node(0, 0, 0), node(1, 1, 0), size(1), i32(2), size(0);          // surface 3 -> "bottom"
  i32(1), node(0, 0, 0), node(1, 1, 1), size(1), i32(1), size(1), i32(3);  // volume 1 -> "liver"
  s += "\n$EndEntities\n$Nodes\n";
  size(2), size(5), size(1), size(9);
  i32(2), i32(3), i32(1), size(3);  // parametric surface block
  size(1), size(2), size(3);
  node(0, 0, 0), real(0.5), real(0.5);
  node(1, 0, 0), real(0.5), real(0.5);
  node(0, 1, 0), real(0.5), real(0.5);
  i32(3), i32(1), i32(0), size(2);
  size(7), size(9);
  node(0, 0, 1), node(1, 1, 1);
  s += "\n$EndNodes\n$Elements\n";
  size(2), size(3), size(1), size(3);
  i32(2), i32(3), i32(2), size(1);
  size(1), size(1), size(3), size(2);
  i32(3), i32(1), i32(4), size(2);
  size(2), size(1), size(2), size(3), size(7);
  size(3), size(2), size(3), size(7), size(9);
  s += "\n$EndElements\n";
  return s;
}

void ExpectTwoTets41(const Mesh& mesh) {
  ASSERT_EQ(mesh.num_nodes(), 5);
  ASSERT_EQ(mesh.num_tets(), 2);
  ASSERT_EQ(mesh.num_triangles(), 1);
  EXPECT_EQ(mesh.nodes.col(4), Vec3(1, 1, 1));
  EXPECT_EQ(mesh.tets.col(0), Eigen::Vector4i(0, 1, 2, 3));
  EXPECT_EQ(mesh.tets.col(1), Eigen::Vector4i(1, 2, 3, 4));
  EXPECT_EQ(mesh.triangles.col(0), Eigen::Vector3i(0, 2, 1));
  ASSERT_NE(mesh.FindGroup("liver"), nullptr);
  EXPECT_EQ(mesh.FindGroup("liver")->dim, 3);
  EXPECT_THAT(mesh.FindGroup("liver")->items, ElementsAre(0, 1));
  ASSERT_NE(mesh.FindGroup("bottom"), nullptr);
  EXPECT_EQ(mesh.FindGroup("bottom")->dim, 2);
  EXPECT_THAT(mesh.FindGroup("bottom")->items, ElementsAre(0));
}

TEST(GmshReader, Reads22AsciiWithPhysicalGroups) {
  Mesh mesh = ReadGmsh(MeshData("two_tets_v22.msh"));
  ASSERT_EQ(mesh.num_nodes(), 5);
  ASSERT_EQ(mesh.num_tets(), 2);
  ASSERT_EQ(mesh.num_triangles(), 2);  // the quad is dropped
  // Tags 10..50 are renumbered 0..4.
  EXPECT_EQ(mesh.tets.col(1), Eigen::Vector4i(1, 2, 3, 4));
  EXPECT_EQ(mesh.triangles.col(0), Eigen::Vector3i(0, 2, 1));
  ASSERT_EQ(mesh.groups.size(), 5u);
  EXPECT_THAT(mesh.FindGroup("liver")->items, ElementsAre(0, 1));
  EXPECT_EQ(mesh.FindGroup("liver")->dim, 3);
  EXPECT_THAT(mesh.FindGroup("bottom")->items, ElementsAre(0));  // only the triangle, not the quad
  EXPECT_EQ(mesh.FindGroup("physical_3")->dim, 2);
  EXPECT_THAT(mesh.FindGroup("physical_3")->items, ElementsAre(1));
  // Groups of lines and points keep their nodes.
  EXPECT_EQ(mesh.FindGroup("edge")->dim, 0);
  EXPECT_THAT(mesh.FindGroup("edge")->items, ElementsAre(0, 1));
  EXPECT_THAT(mesh.FindGroup("apex")->items, ElementsAre(4));
}

TEST(GmshReader, Reads10FormatWithPhysicalTags) {
  Mesh mesh = ReadGmsh(MeshData("single_tet_v1.msh"));
  EXPECT_EQ(mesh.num_nodes(), 4);
  EXPECT_EQ(mesh.num_tets(), 1);
  EXPECT_EQ(mesh.num_triangles(), 1);
  EXPECT_THAT(mesh.FindGroup("physical_1")->items, ElementsAre(0));
  EXPECT_EQ(mesh.FindGroup("physical_2")->dim, 2);
}

TEST(GmshReader, ReadsLiverSampleInFormat10) {
  Mesh mesh = ReadGmsh(test::SharedData("liver/liver.msh"));
  EXPECT_EQ(mesh.num_nodes(), 181);
  EXPECT_EQ(mesh.num_tets(), 596);
  EXPECT_EQ(mesh.num_triangles(), 0);
  ASSERT_NE(mesh.FindGroup("physical_1"), nullptr);
  EXPECT_EQ(mesh.FindGroup("physical_1")->items.size(), 596u);
}

TEST(GmshReader, Reads41AsciiWithEntityPhysicalGroups) {
  ExpectTwoTets41(ReadGmsh(MeshData("two_tets_v41.msh")));
}

TEST(GmshReader, Reads41BinaryLikeAscii) {
  auto path = WriteBytes(Scratch("two_tets.msh"), TwoTets41Binary(false));
  ExpectTwoTets41(ReadGmsh(path));
}

TEST(GmshReader, Reads41BinaryOfOtherByteOrder) {
  auto path = WriteBytes(Scratch("two_tets_swapped.msh"), TwoTets41Binary(true));
  ExpectTwoTets41(ReadGmsh(path));
}

TEST(GmshReader, Reads22Binary) {
  std::string s = "$MeshFormat\n2.2 1 8\n";
  Put<std::int32_t>(s, 1);
  s += "\n$EndMeshFormat\n$Nodes\n5\n";
  const double xyz[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  for (int i = 0; i < 5; ++i) {
    Put<std::int32_t>(s, 10 * (i + 1));
    for (double c : xyz[i]) Put(s, c);
  }
  s += "\n$EndNodes\n$Elements\n3\n";
  for (std::int32_t v : {2, 1, 2, /*elem*/ 1, 2, 0, 10, 30, 20}) Put(s, v);
  for (std::int32_t v : {4, 2, 2, 2, 1, 0, 10, 20, 30, 40, 3, 1, 0, 20, 30, 40, 50}) Put(s, v);
  s += "\n$EndElements\n";
  Mesh mesh = ReadGmsh(WriteBytes(Scratch("binary22.msh"), s));
  EXPECT_EQ(mesh.num_nodes(), 5);
  EXPECT_EQ(mesh.num_tets(), 2);
  EXPECT_EQ(mesh.num_triangles(), 1);
  EXPECT_EQ(mesh.tets.col(1), Eigen::Vector4i(1, 2, 3, 4));
  EXPECT_THAT(mesh.FindGroup("physical_2")->items, ElementsAre(0));
  EXPECT_THAT(mesh.FindGroup("physical_1")->items, ElementsAre(0, 1));
}

/// two_tets_v22.msh with `from` replaced by `to`, written to a scratch file named `name`.
std::filesystem::path Edited22(std::string_view name, std::string_view from, std::string_view to) {
  std::string text = test::ReadBytes(MeshData("two_tets_v22.msh"));
  std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos);
  text.replace(at, from.size(), to);
  return WriteBytes(Scratch(name), text);
}

// Second order: the corners make the linear mesh, the edges' middle nodes its second-order
// geometry (the one off its midpoint, on edge 10-20, kept where it is), and a physical curve's
// 3-node line keeps only its end nodes.
TEST(GmshReader, ReadsSecondOrderElementsWithTheirEdgeNodesApart) {
  Mesh mesh = ReadGmsh(MeshData("two_tets_order2_v22.msh"));
  EXPECT_EQ(mesh.num_nodes(), 5);
  EXPECT_EQ(mesh.num_tets(), 2);
  EXPECT_EQ(mesh.num_triangles(), 1);
  EXPECT_EQ(mesh.tets.col(1), Eigen::Vector4i(1, 2, 3, 4));
  EXPECT_EQ(mesh.triangles.col(0), Eigen::Vector3i(0, 2, 1));
  EXPECT_THAT(mesh.FindGroup("edge")->items, ElementsAre(0, 1));
  ASSERT_EQ(mesh.edge_node_ends.cols(), 9);
  for (Index k = 0; k < 9; ++k) {
    const int a = mesh.edge_node_ends(0, k), b = mesh.edge_node_ends(1, k);
    EXPECT_LT(a, b);
    const Vec3 midpoint = 0.5 * (mesh.nodes.col(a) + mesh.nodes.col(b));
    const Vec3 expected = a == 0 && b == 1 ? Vec3(0.5, -0.1, 0) : midpoint;
    EXPECT_EQ(mesh.edge_nodes.col(k), expected) << "edge " << a << "-" << b;
  }
  // Scaling and moving the mesh moves the edge nodes with it.
  mesh.Transform(2, Vec3(1, 0, 0));
  EXPECT_EQ(mesh.edge_nodes.col(0), Vec3(2, -0.2, 0));
}

TEST(GmshReader, RejectsSecondOrderElementsThatDisagreeOnAnEdgeNode) {
  std::string text = test::ReadBytes(MeshData("two_tets_order2_v22.msh"));
  text.replace(text.find("14\n"), 3, "15\n");
  text.replace(text.find("$EndNodes"), 0, "110 0.5 0.6 0\n");
  text.replace(text.find("20 30 40 50 102"), 15, "20 30 40 50 110");
  auto path = WriteBytes(Scratch("nonconforming.msh"), text);
  EXPECT_THAT(InputErrorMessage([&] { ReadGmsh(path); }),
              HasSubstr("element 4 puts node 110 in the middle of the edge between nodes 20 and "
                        "30, where another element has a node elsewhere"));
}

TEST(GmshReader, ReportsFileAndLineOfShortTetrahedron) {
  auto path = Edited22("cube.msh", "6 4 2 1 1 20 30 40 50", "6 4 2 1 1 20 30 40");
  EXPECT_EQ(InputErrorMessage([&] { ReadGmsh(path); }),
            path.string() + ": line 26: expected 4 node indices for a tetrahedron, got 3");
}

TEST(GmshReader, RejectsUndefinedNodeTag) {
  auto path = Edited22("undefined.msh", "5 4 2 1 1 10 20 30 40", "5 4 2 1 1 10 20 30 99");
  EXPECT_EQ(InputErrorMessage([&] { ReadGmsh(path); }),
            path.string() + ": line 25: element 5 refers to undefined node 99");
}

TEST(GmshReader, RejectsMalformedCoordinate) {
  auto path = Edited22("bad_number.msh", "40 0 0 1", "40 0 0 1x");
  EXPECT_THAT(InputErrorMessage([&] { ReadGmsh(path); }),
              HasSubstr("line 16: expected a z coordinate (a finite number), got '1x'"));
}

TEST(GmshReader, RejectsNanCoordinate) {
  auto path = Edited22("nan.msh", "40 0 0 1", "40 0 nan 1");
  EXPECT_THAT(InputErrorMessage([&] { ReadGmsh(path); }),
              HasSubstr("line 16: expected a y coordinate (a finite number), got 'nan'"));
}

TEST(GmshReader, RejectsDuplicateNodeTag) {
  auto path = Edited22("duplicate.msh", "50 1 1 1", "40 1 1 1");
  EXPECT_THAT(InputErrorMessage([&] { ReadGmsh(path); }),
              HasSubstr("line 17: node tag 40 is defined twice"));
}

TEST(GmshReader, RejectsHugeNodeCountBeforeAllocating) {
  auto path = Edited22("huge.msh", "$Nodes\n5\n", "$Nodes\n999999999999\n");
  EXPECT_THAT(InputErrorMessage([&] { ReadGmsh(path); }),
              HasSubstr("line 12: declares 999999999999 nodes, but only"));
}

TEST(GmshReader, RejectsTooFewNodesBeforeSectionEnd) {
  auto path = Edited22("few.msh", "$Nodes\n5\n", "$Nodes\n6\n");
  EXPECT_THAT(InputErrorMessage([&] { ReadGmsh(path); }),
              HasSubstr("line 18: expected 6 nodes as declared, got 5 before $EndNodes"));
}

TEST(GmshReader, SkipsUnknownSections) {
  auto path =
      Edited22("comments.msh", "$Nodes\n", "$Comments\nanything $Nodes\n$EndComments\n$Nodes\n");
  EXPECT_EQ(ReadGmsh(path).num_tets(), 2);
}

TEST(GmshReader, RejectsUnsupportedVersion) {
  auto path = Edited22("v40.msh", "2.2 0 8", "4 0 8");
  EXPECT_THAT(InputErrorMessage([&] { ReadGmsh(path); }),
              HasSubstr("line 2: unsupported Gmsh format version 4"));
}

TEST(GmshReader, RejectsTruncatedBinaryWithByteOffset) {
  std::string bytes = TwoTets41Binary(false);
  bytes.resize(bytes.find("$Nodes") + 60);
  auto path = WriteBytes(Scratch("truncated.msh"), bytes);
  std::string message = InputErrorMessage([&] { ReadGmsh(path); });
  EXPECT_THAT(message, HasSubstr(path.string() + ": byte offset "));
  EXPECT_THAT(message, HasSubstr("in $Nodes"));
}

TEST(GmshReader, RejectsBadEndiannessCheck) {
  std::string bytes = TwoTets41Binary(false);
  bytes[bytes.find("4.1 1 8\n") + 8] = 7;
  auto path = WriteBytes(Scratch("endianness.msh"), bytes);
  EXPECT_THAT(InputErrorMessage([&] { ReadGmsh(path); }),
              HasSubstr("byte offset 20: expected the binary endianness check integer 1"));
}

TEST(GmshReader, SurvivesEveryTruncationOfBinary) {
  // Every prefix either fails with InputError or (when cut between sections) is a valid mesh.
  const std::string bytes = TwoTets41Binary(false);
  const std::size_t rejected =
      CountRejectedPrefixes(bytes, Scratch("cut.msh"), [](const auto& p) { return ReadGmsh(p); });
  EXPECT_GT(rejected + 10, bytes.size());
}

TEST(GmshReader, RejectsMissingFile) {
  EXPECT_EQ(InputErrorMessage([] { ReadGmsh("/nonexistent/x.msh"); }),
            "/nonexistent/x.msh: cannot open mesh file for reading: No such file or directory");
}

}  // namespace
}  // namespace gipsi
