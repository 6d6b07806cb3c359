// Reading one block of a Gmsh mesh (formats 1.0, 2.x and 4.1) without the whole mesh
// (io/gmsh_block_reader.h), against the whole-file reader's mesh sliced into the same block.

#include "gipsi/io/gmsh_block_reader.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/io/mesh_io.h"
#include "io/io_test_util.h"
#include "temp_dir.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

// Writes Gmsh 4.1 text or binary records.
class Writer {
 public:
  explicit Writer(bool binary) : binary_(binary) {}
  void Line(const std::string& text) { out_ += text + "\n"; }
  void Int(int v) { binary_ ? Raw(v) : Text(std::to_string(v)); }
  void Size(std::uint64_t v) { binary_ ? Raw(v) : Text(std::to_string(v)); }
  void Double(double v) { binary_ ? Raw(v) : Text(fmt::format("{:.17g}", v)); }
  void EndRecord() {
    if (!binary_) out_ += "\n";
  }
  void EndSection(const std::string& marker) {
    if (binary_) out_ += "\n";
    Line(marker);
  }
  const std::string& text() const { return out_; }

 private:
  template <class T>
  void Raw(T v) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));
    out_.append(bytes, sizeof(T));
  }
  void Text(const std::string& v) {
    if (!out_.empty() && out_.back() != '\n') out_ += ' ';
    out_ += v;
  }
  bool binary_;
  std::string out_;
};

// A box as Gmsh 4.1: the nodes in two blocks, with tags 1..N or 7, 10, 13, ... (`sparse`);
// a point, two lines, the boundary triangles in two surfaces and the tets in one volume, with
// physical groups: the volume "tissue" (10), surface 1 unnamed (20), surface 2 "tissue" too
// (21, which ReadGmsh renames "tissue_dim2"), the curve unnamed (30) and the point "apex" (40).
std::string BoxAsGmsh41(const Mesh& box, bool binary, bool sparse) {
  Writer w(binary);
  w.Line("$MeshFormat");
  w.Line(binary ? "4.1 1 8" : "4.1 0 8");
  if (binary) {
    w.Int(1);
    w.EndSection("$EndMeshFormat");
  } else {
    w.Line("$EndMeshFormat");
  }
  w.Line("$PhysicalNames");
  w.Line("3");
  w.Line("3 10 \"tissue\"");
  w.Line("2 21 \"tissue\"");
  w.Line("0 40 \"apex\"");
  w.Line("$EndPhysicalNames");
  w.Line("$Entities");
  for (int count : {1, 1, 2, 1}) w.Size(static_cast<std::uint64_t>(count));
  w.EndRecord();
  auto entity = [&](int dim, int tag, int physical) {
    w.Int(tag);
    for (int k = 0; k < (dim == 0 ? 3 : 6); ++k) w.Double(0.0);
    w.Size(physical != 0 ? 1 : 0);
    if (physical != 0) w.Int(physical);
    if (dim > 0) w.Size(0);
    w.EndRecord();
  };
  entity(0, 1, 40);
  entity(1, 1, 30);
  entity(2, 1, 20);
  entity(2, 2, 21);
  entity(3, 1, 10);
  w.EndSection("$EndEntities");

  const auto n = static_cast<std::uint64_t>(box.num_nodes());
  auto tag = [sparse](Index i) { return sparse ? 7 + 3 * static_cast<std::uint64_t>(i) : i + 1; };
  w.Line("$Nodes");
  w.Size(2);
  w.Size(n);
  w.Size(tag(0));
  w.Size(tag(box.num_nodes() - 1));
  w.EndRecord();
  const Index half = box.num_nodes() / 2;
  for (auto [first, last] : {std::pair<Index, Index>{0, half}, {half, box.num_nodes()}}) {
    w.Int(first == 0 ? 3 : 2);
    w.Int(1);
    w.Int(0);
    w.Size(static_cast<std::uint64_t>(last - first));
    w.EndRecord();
    for (Index i = first; i < last; ++i) {
      w.Size(tag(i));
      w.EndRecord();
    }
    for (Index i = first; i < last; ++i) {
      for (int k = 0; k < 3; ++k) w.Double(box.nodes(k, i));
      w.EndRecord();
    }
  }
  w.EndSection("$EndNodes");

  w.Line("$Elements");
  const Index tris = box.num_triangles(), tri_half = tris / 2;
  const auto all = static_cast<std::uint64_t>(3 + tris + box.num_tets());
  w.Size(5);
  w.Size(all);
  w.Size(1);
  w.Size(all);
  w.EndRecord();
  std::uint64_t element = 1;
  auto block = [&](int dim, int entity_tag, int type,
                   const std::vector<std::vector<Index>>& items) {
    w.Int(dim);
    w.Int(entity_tag);
    w.Int(type);
    w.Size(items.size());
    w.EndRecord();
    for (const auto& nodes : items) {
      w.Size(element++);
      for (Index v : nodes) w.Size(tag(v));
      w.EndRecord();
    }
  };
  block(0, 1, 15, {{0}});
  block(1, 1, 1, {{0, 1}, {1, 2}});
  std::vector<std::vector<Index>> first, second, tets;
  for (Index t = 0; t < tris; ++t)
    (t < tri_half ? first : second)
        .push_back({box.triangles(0, t), box.triangles(1, t), box.triangles(2, t)});
  for (Index e = 0; e < box.num_tets(); ++e)
    tets.push_back({box.tets(0, e), box.tets(1, e), box.tets(2, e), box.tets(3, e)});
  block(2, 1, 2, first);
  block(2, 2, 2, second);
  block(3, 1, 4, tets);
  w.EndSection("$EndElements");
  return w.text();
}

// Every block, on 1, 3 and 7 processes, of a box written as ASCII and binary Gmsh 4.1, with
// node tags 1..N and with other tags, is the whole-file reader's mesh sliced into that block:
// nodes, tets, triangles, element tags, and the groups with ReadGmsh's names.
TEST(GmshBlockReader, EveryBlockIsTheWholeReadersSlice) {
  const std::filesystem::path dir = testing::TestTempDir();
  const Mesh box = MakeTetBox(Vec3::Zero(), Vec3(2, 1, 1), {4, 3, 2});
  for (bool binary : {false, true}) {
    for (bool sparse : {false, true}) {
      const auto path = dir / fmt::format("box_{}_{}.msh", binary, sparse);
      std::ofstream(path, std::ios::binary) << BoxAsGmsh41(box, binary, sparse);
      const Mesh whole = ReadMesh(path);
      ASSERT_EQ(whole.num_tets(), box.num_tets());
      ASSERT_EQ(whole.groups.size(), 5U);
      EXPECT_EQ(whole.groups[1].name, "tissue_dim2");
      for (int size : {1, 3, 7}) {
        for (int rank = 0; rank < size; ++rank) {
          const auto block = ReadGmshBlock(path, rank, size);
          ASSERT_TRUE(block.has_value());
          test::ExpectSameBlock(
              *block, BlockOfMesh(whole, rank, size),
              fmt::format("binary {}, sparse tags {}, block {} of {}", binary, sparse, rank, size));
        }
      }
    }
  }
}

// The same box as Gmsh 1.0 (`version` "1.0": $NOD/$ELM, no names) or 2.2 ("2.2", ASCII or
// binary): one element per line (binary: blocks of one type), the first tag the physical group.
std::string BoxAsGmsh2(const Mesh& box, const std::string& version, bool binary, bool sparse) {
  const bool v1 = version == "1.0";
  Writer w(binary);
  if (!v1) {
    w.Line("$MeshFormat");
    w.Line(version + (binary ? " 1 8" : " 0 8"));
    if (binary) {
      w.Int(1);
      w.EndSection("$EndMeshFormat");
    } else {
      w.Line("$EndMeshFormat");
    }
    w.Line("$PhysicalNames");
    w.Line("3");
    w.Line("3 10 \"tissue\"");
    w.Line("2 21 \"tissue\"");
    w.Line("0 40 \"apex\"");
    w.Line("$EndPhysicalNames");
  }
  auto tag = [sparse](Index i) { return sparse ? 7 + 3 * static_cast<int>(i) : int(i) + 1; };
  w.Line(v1 ? "$NOD" : "$Nodes");
  w.Line(std::to_string(box.num_nodes()));
  for (Index i = 0; i < box.num_nodes(); ++i) {
    w.Int(tag(i));
    for (int k = 0; k < 3; ++k) w.Double(box.nodes(k, i));
    w.EndRecord();
  }
  w.EndSection(v1 ? "$ENDNOD" : "$EndNodes");

  struct Item {
    int type, physical;
    std::vector<Index> nodes;
  };
  std::vector<Item> items = {{15, 40, {0}}, {1, 30, {0, 1}}, {1, 30, {1, 2}}};
  const Index tris = box.num_triangles();
  for (Index t = 0; t < tris; ++t)
    items.push_back({2,
                     t < tris / 2 ? 20 : 21,
                     {box.triangles(0, t), box.triangles(1, t), box.triangles(2, t)}});
  for (Index e = 0; e < box.num_tets(); ++e)
    items.push_back({4, 10, {box.tets(0, e), box.tets(1, e), box.tets(2, e), box.tets(3, e)}});
  w.Line(v1 ? "$ELM" : "$Elements");
  w.Line(std::to_string(items.size()));
  for (std::size_t i = 0; i < items.size(); ++i) {
    const Item& item = items[i];
    if (binary) {  // a block per element, as a writer that does not group them
      w.Int(item.type);
      w.Int(1);
      w.Int(2);
    }
    w.Int(static_cast<int>(i) + 1);
    if (!binary) w.Int(item.type);
    if (v1) {
      w.Int(item.physical);
      w.Int(1);
      w.Int(static_cast<int>(item.nodes.size()));
    } else {
      if (!binary) w.Int(2);
      w.Int(item.physical);
      w.Int(1);
    }
    for (Index v : item.nodes) w.Int(tag(v));
    w.EndRecord();
  }
  w.EndSection(v1 ? "$ENDELM" : "$EndElements");
  return w.text();
}

// Every block of the box as Gmsh 1.0, 2.2 ASCII and 2.2 binary is the whole reader's slice.
TEST(GmshBlockReader, EveryBlockOfAnOlderFormatIsTheWholeReadersSlice) {
  const std::filesystem::path dir = testing::TestTempDir();
  const Mesh box = MakeTetBox(Vec3::Zero(), Vec3(2, 1, 1), {4, 3, 2});
  for (const auto& [version, binary] :
       std::vector<std::pair<std::string, bool>>{{"1.0", false}, {"2.2", false}, {"2.2", true}}) {
    for (bool sparse : {false, true}) {
      const auto path = dir / fmt::format("box_{}_{}_{}.msh", version, binary, sparse);
      std::ofstream(path, std::ios::binary) << BoxAsGmsh2(box, version, binary, sparse);
      const Mesh whole = ReadMesh(path);
      ASSERT_EQ(whole.num_tets(), box.num_tets());
      ASSERT_EQ(whole.groups.size(), 5U);
      if (version != "1.0") {
        EXPECT_EQ(whole.groups[1].name, "tissue_dim2");
      }
      for (int size : {1, 3, 7}) {
        for (int rank = 0; rank < size; ++rank) {
          const auto block = ReadGmshBlock(path, rank, size);
          ASSERT_TRUE(block.has_value());
          test::ExpectSameBlock(*block, BlockOfMesh(whole, rank, size),
                                fmt::format("format {}, binary {}, sparse tags {}, block {} of {}",
                                            version, binary, sparse, rank, size));
        }
      }
    }
  }
}

// Second-order elements and a file of two node or element sections are not read in blocks (the
// caller reads the whole file instead); mistakes are named with the file and the line or byte
// offset.
TEST(GmshBlockReader, OtherFilesAreLeftToTheWholeReaderAndMistakesAreNamed) {
  const std::filesystem::path dir = testing::TestTempDir();
  auto write = [&](const std::string& name, const std::string& text) {
    const auto path = dir / name;
    std::ofstream(path, std::ios::binary) << text;
    return path;
  };
  const std::string v2_head =
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n"
      "4 0 0 1\n$EndNodes\n";
  const auto v2_second = write("v2_p2.msh", v2_head +
                                                "$Elements\n1\n1 11 2 1 1 1 2 3 4 1 2 3 4 1 2\n"
                                                "$EndElements\n");
  EXPECT_FALSE(ReadGmshBlock(v2_second, 0, 2).has_value());
  const auto two_sections =
      write("two.msh", "$NOD\n1\n1 0 0 0\n$ENDNOD\n$NOD\n1\n2 1 0 0\n$ENDNOD\n");
  EXPECT_FALSE(ReadGmshBlock(two_sections, 0, 2).has_value());
  const auto two_element_sections =
      write("two_elements.msh", v2_head + "$Elements\n1\n1 4 2 1 1 1 2 3 4\n$EndElements\n" +
                                    "$Elements\n1\n2 4 2 1 1 1 2 4 3\n$EndElements\n");
  EXPECT_EQ(ReadMesh(two_element_sections).num_tets(), 2);
  EXPECT_FALSE(ReadGmshBlock(two_element_sections, 0, 2).has_value());
  const auto v3 = write("v3.msh", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n");
  EXPECT_FALSE(ReadGmshBlock(v3, 0, 2).has_value());  // ReadMesh says why it is refused
  const std::string head =
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n"
      "0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n";
  const auto second = write("p2.msh", head +
                                          "$Elements\n1 1 1 1\n3 1 11 1\n"
                                          "1 1 2 3 4 1 2 3 4 1 2\n$EndElements\n");
  EXPECT_FALSE(ReadGmshBlock(second, 0, 2).has_value());

  // The block reader's message, which must be the whole reader's.
  auto error = [](const std::filesystem::path& path) {
    std::string block = "no error", whole = "no error";
    try {
      (void)ReadGmshBlock(path, 1, 2);
    } catch (const InputError& e) {
      block = e.what();
    }
    try {
      (void)ReadMesh(path);
    } catch (const InputError& e) {
      whole = e.what();
    }
    EXPECT_EQ(block, whole);
    return block;
  };
  const auto undefined =
      write("undefined.msh", head + "$Elements\n1 1 1 1\n3 1 4 1\n9 1 2 3 5\n$EndElements\n");
  EXPECT_THAT(error(undefined), HasSubstr("undefined.msh: line 19: element 9 refers to "
                                          "undefined node 5"));
  const auto truncated = write("truncated.msh", head + "$Elements\n1 1 1 1\n3 1 4 1\n");
  EXPECT_THAT(error(truncated), HasSubstr("truncated.msh: line 18: declares 1 elements"));
  const auto short_line =
      write("short.msh", head + "$Elements\n1 1 1 1\n3 1 4 1\n9 1 2 3\n$EndElements\n");
  EXPECT_THAT(error(short_line),
              HasSubstr("short.msh: line 19: expected 4 node indices for a tetrahedron, got 3"));
  const auto nan = write("nan.msh",
                         "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n"
                         "3 1 0 1\n1\n0 nan 0\n$EndNodes\n");
  EXPECT_THAT(error(nan), HasSubstr("nan.msh: line 8: expected a y coordinate"));
  // The same in format 2.2 and 1.0.
  EXPECT_THAT(
      error(write("undefined2.msh", v2_head + "$Elements\n1\n9 4 2 1 1 1 2 3 5\n$EndElements\n")),
      HasSubstr("undefined2.msh: line 13: element 9 refers to undefined node 5"));
  EXPECT_THAT(error(write("truncated2.msh", v2_head + "$Elements\n2\n9 4 2 1 1 1 2 3 4\n")),
              HasSubstr("truncated2.msh: line 12: declares 2 elements"));
  EXPECT_THAT(error(write("short2.msh", v2_head + "$Elements\n1\n9 4 2 1 1 1 2 3\n$EndElements\n")),
              HasSubstr("short2.msh: line 13: expected 4 node indices for a tetrahedron, got 3"));
  EXPECT_THAT(error(write("few2.msh",
                          "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n"
                          "1 0 0 0\n$EndNodes\n")),
              HasSubstr("few2.msh: line 7: expected 2 nodes as declared, got 1 before $EndNodes"));
  EXPECT_THAT(error(write("nan1.msh", "$NOD\n2\n1 0 0 0\n2 0 0 inf\n$ENDNOD\n")),
              HasSubstr("nan1.msh: line 4: expected a z coordinate"));
  EXPECT_THAT(error(write("count1.msh",
                          "$NOD\n1\n1 0 0 0\n$ENDNOD\n$ELM\n1\n"
                          "1 4 1 1 3 1 1 1 1\n$ENDELM\n")),
              HasSubstr("count1.msh: line 7: expected 3 node indices as declared, got 4"));
  EXPECT_THAT(error(write("size2.msh", "$MeshFormat\n2.2 0 4\n$EndMeshFormat\n")),
              HasSubstr("size2.msh: line 2: unsupported data size 4"));
  EXPECT_THAT(error(dir / "missing.msh"),
              HasSubstr("missing.msh: cannot open mesh file for reading"));
  std::filesystem::create_directory(dir / "folder.msh");
  EXPECT_THAT(error(dir / "folder.msh"), HasSubstr("is a directory, expected a mesh file"));
}

}  // namespace
}  // namespace gipsi
