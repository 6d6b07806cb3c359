#include "gipsi/io/tetgen_reader.h"

#include <cstdint>
#include <functional>
#include <string>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh_block.h"
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

// `mesh` written as TetGen files STEM.node, STEM.ele and STEM.face, node i numbered number(i),
// with a region attribute per tet (1 below x = 1, 2.5 above) and a boundary marker per face,
// between comments and blank lines.
void WriteTetGen(const Mesh& mesh, const std::filesystem::path& stem,
                 const std::function<std::int64_t(Index)>& number) {
  std::string node = fmt::format("# a box\n{} 3 0 0\n", mesh.num_nodes());
  for (Index i = 0; i < mesh.num_nodes(); ++i)
    node += fmt::format("{} {} {} {}{}\n", number(i), mesh.nodes(0, i), mesh.nodes(1, i),
                        mesh.nodes(2, i), i % 5 == 0 ? "  # every fifth\n" : "");
  std::string ele = fmt::format("{} 4 1\n\n", mesh.num_tets());
  for (Index e = 0; e < mesh.num_tets(); ++e) {
    const double x = 0.25 * (mesh.nodes(0, mesh.tets(0, e)) + mesh.nodes(0, mesh.tets(1, e)) +
                             mesh.nodes(0, mesh.tets(2, e)) + mesh.nodes(0, mesh.tets(3, e)));
    ele +=
        fmt::format("{} {} {} {} {} {}\n", e + 1, number(mesh.tets(0, e)), number(mesh.tets(1, e)),
                    number(mesh.tets(2, e)), number(mesh.tets(3, e)), x < 1 ? "1" : "2.5");
  }
  std::string face = fmt::format("{} 1\n", mesh.num_triangles());
  for (Index t = 0; t < mesh.num_triangles(); ++t)
    face += fmt::format("{} {} {} {} {}\n", t + 1, number(mesh.triangles(0, t)),
                        number(mesh.triangles(1, t)), number(mesh.triangles(2, t)), 3 + t % 4);
  WriteBytes(std::filesystem::path(stem).concat(".node"), node);
  WriteBytes(std::filesystem::path(stem).concat(".ele"), ele);
  WriteBytes(std::filesystem::path(stem).concat(".face"), face);
}

// Every block, on 1, 3 and 7 processes, of a box written as TetGen files is the whole reader's
// mesh sliced into that block (nodes, tets, faces, the region and marker groups), with node
// numbers from 1, from 0, spread out (a table from number to node), and consecutive for a
// while and then not (the table made part way through).
TEST(TetGenReader, EveryBlockIsTheWholeReadersSlice) {
  const Mesh box = MakeTetBox(Vec3::Zero(), Vec3(2, 1, 1), {4, 3, 2});
  const std::vector<std::pair<std::string, std::function<std::int64_t(Index)>>> numberings = {
      {"from1", [](Index i) { return i + 1; }},
      {"from0", [](Index i) { return i; }},
      {"spread", [](Index i) { return 10 * i + 7; }},
      {"jump", [](Index i) { return i < 9 ? i + 1 : i + 100; }}};
  for (const auto& [name, number] : numberings) {
    const auto stem = Scratch("box_" + name);
    WriteTetGen(box, stem, number);
    const Mesh whole = ReadTetGen(std::filesystem::path(stem).concat(".ele"));
    ASSERT_EQ(whole.nodes, box.nodes) << name;
    ASSERT_EQ(whole.tets, box.tets) << name;
    ASSERT_EQ(whole.triangles, box.triangles) << name;
    ASSERT_EQ(whole.groups.size(), 6U) << name;  // region_1, region_2.5, marker_3..6
    EXPECT_EQ(whole.groups[1].name, "region_2.5");
    for (int size : {1, 3, 7})
      for (int rank = 0; rank < size; ++rank)
        test::ExpectSameBlock(
            ReadTetGenBlock(std::filesystem::path(stem).concat(".node"), rank, size),
            BlockOfMesh(whole, rank, size), fmt::format("{}, block {} of {}", name, rank, size));
  }
}

// A block reader meets every mistake the whole reader meets, wherever it lies in the files
// (every process reads every line), and names it alike.
TEST(TetGenReader, EveryBlockReportsTheWholeReadersErrors) {
  auto error = [](const std::filesystem::path& path) {
    std::string block = "no error", whole = "no error";
    try {
      (void)ReadTetGenBlock(path, 1, 2);
    } catch (const InputError& e) {
      block = e.what();
    }
    try {
      (void)ReadTetGen(path);
    } catch (const InputError& e) {
      whole = e.what();
    }
    EXPECT_EQ(block, whole);
    return block;
  };
  const std::string nodes = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
  WriteBytes(Scratch("undefined.node"), nodes);
  const auto undefined = WriteBytes(Scratch("undefined.ele"), "2 4 0\n1 1 2 3 4\n2 1 2 3 9\n");
  EXPECT_EQ(error(undefined), undefined.string() + ": line 3: refers to undefined node 9");
  const auto twice = WriteBytes(Scratch("twice.node"), "3 3 0 0\n1 0 0 0\n5 1 0 0\n1 0 1 0\n");
  WriteBytes(Scratch("twice.ele"), "0 4 0\n");
  EXPECT_EQ(error(twice), twice.string() + ": line 4: point 1 is defined twice");
  WriteBytes(Scratch("short.node"), nodes);
  WriteBytes(Scratch("short.ele"), "1 4 0\n1 1 2 3 4\n");
  const auto face = WriteBytes(Scratch("short.face"), "2 1\n1 1 2 3 7\n2 1 2 4\n");
  EXPECT_EQ(error(face), face.string() +
                             ": line 3: expected 3 node indices and a marker for a face, got 3 "
                             "values");
  const auto truncated = WriteBytes(Scratch("cut.node"), "4 3 0 0\n1 0 0 0\n2 1 0 0\n");
  EXPECT_THAT(error(truncated), HasSubstr("cut.node: line 1: declares 4 points"));
  // A header whose attribute count would overflow the line's token count (a signed overflow).
  const auto attributes = WriteBytes(Scratch("many.node"), "1 3 9223372036854775807 0\n1 0 0 0\n");
  EXPECT_EQ(error(attributes), attributes.string() +
                                   ": line 1: expected a number of attributes up to 1000000, got "
                                   "9223372036854775807");
}

}  // namespace
}  // namespace gipsi
