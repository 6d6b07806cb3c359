// Reading one block of a legacy VTK unstructured grid without the whole mesh
// (ReadVtkLegacyBlock), against the whole-file reader's mesh sliced into the same block.

#include <cstdint>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/io/vtk_legacy_reader.h"
#include "io/io_test_util.h"

namespace gipsi {
namespace {

using test::BoxCells;
using test::Put;
using test::Scratch;
using test::VtkCell;
using test::WriteBytes;
using ::testing::HasSubstr;

const bool kSwap = test::LittleEndianHost();  // legacy VTK binary is big-endian

// The box as a legacy VTK unstructured grid: ASCII or BINARY, the classic cell layout or VTK
// 5.1's OFFSETS/CONNECTIVITY; a FIELD before the points, METADATA after them, and CELL_DATA at
// the end, which the readers skip.
std::string BoxAsVtk(const Mesh& box, bool binary, bool layout51) {
  std::string s = fmt::format("# vtk DataFile Version {}\nbox\n{}\nDATASET UNSTRUCTURED_GRID\n",
                              layout51 ? "5.1" : "3.0", binary ? "BINARY" : "ASCII");
  auto values = [&](const auto& list, auto as) {
    for (const auto v : list) {
      if (binary)
        Put(s, static_cast<decltype(as)>(v), kSwap);
      else
        s += fmt::format("{} ", v);
    }
    s += "\n";
  };
  s += "FIELD FieldData 1\nTIME 1 1 double\n";
  values(std::vector<double>{0.5}, double{});
  s += fmt::format("POINTS {} double\n", box.num_nodes());
  std::vector<double> coords(box.nodes.data(), box.nodes.data() + box.nodes.size());
  if (binary) {
    values(coords, double{});
  } else {
    for (double c : coords) s += fmt::format("{:.17g} ", c);
    s += "\n";
  }
  s += "METADATA\nINFORMATION 0\n\n";
  const std::vector<VtkCell> cells = BoxCells(box);
  std::vector<std::int64_t> offsets{0}, connectivity, classic, types;
  for (const VtkCell& cell : cells) {
    classic.push_back(static_cast<std::int64_t>(cell.points.size()));
    for (Index p : cell.points) {
      classic.push_back(p);
      connectivity.push_back(p);
    }
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
    types.push_back(cell.type);
  }
  if (layout51) {
    s += fmt::format("CELLS {} {}\nOFFSETS vtktypeint64\n", offsets.size(), connectivity.size());
    values(offsets, std::int64_t{});
    s += "CONNECTIVITY vtktypeint64\n";
    values(connectivity, std::int64_t{});
  } else {
    s += fmt::format("CELLS {} {}\n", cells.size(), classic.size());
    values(classic, std::int32_t{});
  }
  s += fmt::format("CELL_TYPES {}\n", cells.size());
  values(types, std::int32_t{});
  s += fmt::format("CELL_DATA {}\nSCALARS id int 1\nLOOKUP_TABLE default\n", cells.size());
  values(types, std::int32_t{});
  return s;
}

// Every block, on 1, 3 and 7 processes, of a box written as ASCII and binary, in both cell
// layouts, is the whole-file reader's mesh sliced into that block: points, tets, triangles.
TEST(VtkLegacyBlockReader, EveryBlockIsTheWholeReadersSlice) {
  const Mesh box = MakeTetBox(Vec3::Zero(), Vec3(2, 1, 1), {4, 3, 2});
  for (bool binary : {false, true}) {
    for (bool layout51 : {false, true}) {
      const auto path = WriteBytes(Scratch(fmt::format("box_{}_{}.vtk", binary, layout51)),
                                   BoxAsVtk(box, binary, layout51));
      const Mesh whole = ReadVtkLegacy(path);
      ASSERT_EQ(whole.num_tets(), box.num_tets());
      ASSERT_EQ(whole.num_triangles(), box.num_triangles());
      for (int size : {1, 3, 7}) {
        for (int rank = 0; rank < size; ++rank) {
          const auto block = ReadVtkLegacyBlock(path, rank, size);
          ASSERT_TRUE(block.has_value());
          test::ExpectSameBlock(*block, BlockOfMesh(whole, rank, size),
                                fmt::format("binary {}, VTK 5.1 layout {}, block {} of {}", binary,
                                            layout51, rank, size));
        }
      }
    }
  }
}

// The whole reader's message for `path` (or "no error"), and the block reader's, which must be
// the same.
std::string SameError(const std::filesystem::path& path) {
  std::string block = "no error", whole = "no error";
  try {
    (void)ReadVtkLegacyBlock(path, 1, 2);
  } catch (const InputError& e) {
    block = e.what();
  }
  try {
    (void)ReadVtkLegacy(path);
  } catch (const InputError& e) {
    whole = e.what();
  }
  EXPECT_EQ(block, whole);
  return block;
}

// Polydata (no tets) and a grid with two cell arrays are left to the whole reader; mistakes are
// the whole reader's, word for word.
TEST(VtkLegacyBlockReader, OtherFilesAreLeftToTheWholeReaderAndMistakesAreNamed) {
  const std::string head =
      "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n"
      "POINTS 5 float\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\n";
  const std::string cells = "CELLS 3 14\n4 0 1 2 3\n4 1 2 3 4\n3 0 1 2\n";
  const std::string types = "CELL_TYPES 3\n10\n10\n5\n";
  auto write = [](const std::string& name, const std::string& text) {
    return WriteBytes(Scratch(name), text);
  };
  EXPECT_FALSE(
      ReadVtkLegacyBlock(write("poly.vtk",
                               "# vtk DataFile Version 3.0\np\nASCII\nDATASET POLYDATA\n"
                               "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\n"),
                         0, 2)
          .has_value());
  EXPECT_FALSE(
      ReadVtkLegacyBlock(write("twice.vtk", head + cells + cells + types), 0, 2).has_value());
  ASSERT_EQ(SameError(write("good.vtk", head + cells + types)), "no error");

  auto replaced = [&](const std::string& name, std::string text, const std::string& from,
                      const std::string& to) {
    text.replace(text.find(from), from.size(), to);
    return write(name, text);
  };
  const std::string good = head + cells + types;
  EXPECT_THAT(SameError(replaced("range.vtk", good, "4 1 2 3 4", "4 1 2 3 7")),
              HasSubstr("range.vtk: line 7 (CELLS): cell 1 refers to point 7, out of range"));
  EXPECT_THAT(SameError(replaced("kind.vtk", good, "10\n10\n5", "10\n5\n10")),
              HasSubstr("expected 3 point indices for a triangle (cell 1), got 4"));
  EXPECT_THAT(SameError(replaced("repeat.vtk", good, "3 0 1 2", "3 0 1 1")),
              HasSubstr("line 7 (CELLS): cell 2 repeats point 1"));
  EXPECT_THAT(SameError(replaced("count.vtk", good, "CELLS 3 14", "CELLS 99 14")),
              HasSubstr("line 7 (CELLS): expected at most 14 cells in 14 values, got a count"));
  EXPECT_THAT(SameError(replaced("size.vtk", good, "CELLS 3 14", "CELLS 2 14")),
              HasSubstr("the size 14 does not match the 2 cells (10 values)"));
  EXPECT_THAT(SameError(replaced("holds.vtk", good, "3 0 1 2", "9 0 1 2")),
              HasSubstr("cell 2 declares 9 points, more than the array holds"));
  EXPECT_THAT(
      SameError(replaced("types.vtk", good, "CELL_TYPES 3\n10\n10\n5", "CELL_TYPES 2\n10\n10")),
      HasSubstr("line 11 (CELL_TYPES): expected 3 cell types (one per cell), got 2"));
  EXPECT_THAT(SameError(write("notypes.vtk", head + cells)),
              HasSubstr("expected a CELL_TYPES section, got end of file"));
  EXPECT_THAT(SameError(replaced("nan.vtk", good, "1 1 1", "1 1 x")),
              HasSubstr("line 6: expected a point coordinate (a finite number), got 'x'"));
  EXPECT_THAT(SameError(replaced("points.vtk", good, "POINTS 5", "POINTS 2000000000")),
              HasSubstr("line 5: declares 2000000000 points, but only"));
  EXPECT_THAT(SameError(replaced("keyword.vtk", good, "CELL_TYPES", "CELL_KINDS")),
              HasSubstr("expected a section keyword"));
  EXPECT_THAT(SameError(replaced("dataset.vtk", good, "UNSTRUCTURED_GRID", "STRUCTURED_POINTS")),
              HasSubstr("line 4: unsupported dataset 'STRUCTURED_POINTS'"));
  const std::string v51 = head +
                          "CELLS 4 11\nOFFSETS vtktypeint64\n0 4 8 11\n"
                          "CONNECTIVITY vtktypeint64\n0 1 2 3 1 2 3 4 0 1 2\n" +
                          types;
  ASSERT_EQ(SameError(write("good51.vtk", v51)), "no error");
  EXPECT_THAT(SameError(replaced("offsets.vtk", v51, "0 4 8 11", "0 4 9 11")),
              HasSubstr("expected 4 point indices for a tetrahedron (cell 1), got 5"));
  EXPECT_THAT(SameError(replaced("falling.vtk", v51, "0 4 8 11", "0 4 3 11")),
              HasSubstr("(CELLS): expected offsets rising from 0 to the connectivity size 11"));
  EXPECT_THAT(SameError(replaced("range51.vtk", v51, "1 2 3 4 0", "1 2 3 5 0")),
              HasSubstr("(CELLS): cell 1 refers to point 5, out of range [0, 5)"));
  EXPECT_THAT(SameError("/nonexistent/x.vtk"),
              HasSubstr("/nonexistent/x.vtk: cannot open mesh file for reading"));
}

// Every strict prefix of a binary file, in either layout, is refused by the block reader exactly
// when the whole reader refuses it, and otherwise gives the whole reader's block: a truncated
// file never yields a partial block.
TEST(VtkLegacyBlockReader, EveryTruncationIsRefusedAsTheWholeReaderRefusesIt) {
  const Mesh box = MakeTetBox(Vec3::Zero(), Vec3(1, 1, 1), {1, 1, 1});
  for (bool layout51 : {false, true}) {
    const std::string bytes = BoxAsVtk(box, true, layout51);
    const auto path = Scratch(fmt::format("cut_{}.vtk", layout51));
    std::size_t refused = 0;
    for (std::size_t n = 0; n < bytes.size(); ++n) {
      WriteBytes(path, bytes.substr(0, n));
      std::optional<Mesh> whole;
      try {
        whole = ReadVtkLegacy(path);
      } catch (const InputError&) {
      }
      std::optional<MeshBlock> block;
      bool block_refused = false;
      try {
        block = ReadVtkLegacyBlock(path, 1, 2);
      } catch (const InputError&) {
        block_refused = true;
      }
      ASSERT_EQ(block_refused, !whole.has_value()) << n << " of " << bytes.size() << " bytes";
      if (whole) {
        ASSERT_TRUE(block.has_value());
        test::ExpectSameBlock(*block, BlockOfMesh(*whole, 1, 2), fmt::format("{} bytes", n));
      }
      refused += block_refused ? 1 : 0;
    }
    EXPECT_GE(refused, bytes.size() * 8 / 10);  // all but cuts in the trailing cell data
  }
}

}  // namespace
}  // namespace gipsi
