/// @file
/// One block of a legacy VTK unstructured grid, streamed (see vtk_legacy_reader.h).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/io/chunked_file.h"
#include "gipsi/io/text_reader.h"
#include "gipsi/io/vtk_legacy_reader.h"
#include "gipsi/io/vtk_legacy_types.h"

namespace gipsi {
namespace {

using internal::ChunkedFile;
using internal::Quote;
using internal::VtkDataType;
using internal::VtkLower;

/// Reads an unstructured grid in two passes. The first checks the file section by section as
/// ReadVtkLegacy does, counts the points and cells and keeps each cell's kind (tet, triangle
/// or other: 2 bits a cell), which CELL_TYPES gives only after CELLS. The second checks every
/// tet and triangle as ReadVtkLegacy does and keeps the block's points, tets and triangles.
class VtkBlockParser {
 public:
  VtkBlockParser(const std::filesystem::path& path, int rank, int size)
      : f_(path), rank_(rank), size_(size) {}

  std::optional<MeshBlock> Read() {
    if (!Pass(false)) return std::nullopt;
    r_ = internal::StartBlock(block_, rank_, size_, num_nodes_, num_tets_, num_triangles_, f_);
    (void)Pass(true);
    return std::move(block_);
  }

 private:
  enum Kind : std::uint8_t { kOther = 0, kTet = 1, kTriangle = 2 };

  // False (first pass) for a file read whole: polydata, a second CELLS or CELL_TYPES section.
  bool Pass(bool extract) {
    f_.Rewind();
    if (!Header()) return false;
    bool have_cells = false, have_types = false;
    std::string_view token;
    while (f_.TryToken(&token)) {
      const std::string key = VtkLower(token);
      if (key == "points") {
        Points(extract);
      } else if (key == "cells") {
        if (have_cells) return false;
        have_cells = true;
        Cells(extract);
      } else if (key == "cell_types") {
        if (have_types) return false;
        have_types = true;
        CellTypes(extract);
      } else if (key == "metadata") {
        SkipMetadata();
      } else if (key == "field") {
        SkipField();
      } else if (key == "point_data" || key == "cell_data") {
        break;
      } else {
        const std::string what = fmt::format(
            "expected a section keyword (POINTS, CELLS, CELL_TYPES, POINT_DATA or CELL_DATA), "
            "got {}",
            Quote(token));
        if (!binary_) f_.Fail(what);
        ThrowInputError(
            f_.source(),
            fmt::format("line {} (byte offset {})", f_.line(), f_.offset() - token.size()),
            what + "; the binary data before it does not match its declared count");
      }
    }
    if (extract) return true;
    if (points_line_ == 0) f_.Fail("expected a POINTS section, got end of file");
    if (num_cells_ > 0 && types_line_ == 0)
      f_.Fail("expected a CELL_TYPES section, got end of file");
    if (types_line_ != 0 && num_types_ != num_cells_)
      FailIn(types_line_, "CELL_TYPES",
             fmt::format("expected {} cell types (one per cell), got {}", num_cells_, num_types_));
    return true;
  }

  [[noreturn]] void FailIn(int line, std::string_view section, std::string_view what) const {
    ThrowInputError(f_.source(), fmt::format("line {} ({})", line, section), what);
  }

  // False for polydata (no tets: read whole).
  bool Header() {
    std::string_view line;
    if (!f_.NextLine(&line) || line.rfind("# vtk DataFile Version", 0) != 0)
      f_.Fail(fmt::format("expected '# vtk DataFile Version x.x', got {}", Quote(line)));
    if (!f_.NextLine(&line)) f_.Fail("expected a title line, got end of file");
    const std::string format = VtkLower(internal::Trim(f_.RequireContentLine("ASCII or BINARY")));
    if (format != "ascii" && format != "binary")
      f_.Fail(fmt::format("expected ASCII or BINARY, got {}", Quote(format)));
    binary_ = format == "binary";
    const auto t = internal::SplitTokens(f_.RequireContentLine("DATASET <type>"));
    if (t.size() != 2 || VtkLower(t[0]) != "dataset")
      f_.Fail("expected 'DATASET UNSTRUCTURED_GRID' or 'DATASET POLYDATA'");
    const std::string kind = VtkLower(t[1]);
    if (kind == "polydata") return false;
    if (kind != "unstructured_grid")
      f_.Fail(fmt::format("unsupported dataset {} (supported: UNSTRUCTURED_GRID, POLYDATA)",
                          Quote(t[1])));
    return true;
  }

  std::int64_t Count(std::string_view what) {
    const std::int64_t n = f_.ToInt(f_.Token(what), what);
    if (n < 0) f_.Fail(fmt::format("expected {} (non-negative), got {}", what, n));
    return n;
  }
  VtkDataType Type() {
    const std::string_view name = f_.Token("a data type");
    const VtkDataType type = internal::ParseVtkDataType(name);
    if (type.bytes == 0) f_.Fail(fmt::format("unsupported data type {}", Quote(name)));
    return type;
  }

  // Reads `n` values of `type` (ASCII tokens, or big-endian binary after the header line), each
  // through `sink(i, value)`: integers exact, reals checked finite.
  template <class Sink>
  void Values(std::int64_t n, VtkDataType type, bool want_int, std::string_view what, Sink sink) {
    if (want_int && type.is_float) f_.Fail(fmt::format("expected an integer type for {}", what));
    if (!binary_) {
      f_.CheckCount(n, 1, what);
      for (std::int64_t i = 0; i < n; ++i) {
        if (want_int)
          sink(i, f_.ToInt(f_.Token(what), what));
        else
          sink(i, f_.ToFinite(f_.Token(what), what));
      }
      return;
    }
    f_.SkipRestOfLine();
    f_.CheckCount(n, static_cast<std::size_t>(type.bytes), what);
    const bool swap = internal::HostIsLittleEndian();
    const auto bytes = static_cast<std::size_t>(type.bytes);
    for (std::int64_t i = 0; i < n; ++i) {
      const char* p = f_.Bytes(bytes, what).data();
      if (!type.is_float) {
        sink(i, internal::LoadVtkInt(p, type, swap));
        continue;
      }
      const double v = internal::LoadVtkReal(p, type, swap);
      if (!std::isfinite(v))
        f_.FailAtOffset(fmt::format("expected {} (a finite number), got {}", what, v),
                        f_.offset() - bytes);
      sink(i, v);
    }
  }

  void Points(bool extract) {
    if (points_line_ != 0 && !extract) f_.Fail("a second POINTS section");
    const int line = f_.line();
    const std::int64_t n = Count("a number of points");
    const VtkDataType type = Type();
    if (!type.is_float) f_.Fail("expected a real data type (float or double) for POINTS");
    f_.CheckCount(n, 3, "points");
    if (!extract) {
      if (n > INT32_MAX) f_.Fail(fmt::format("{} points: more than 2^31 - 1", n));
      points_line_ = line;
      num_nodes_ = n;
    }
    const std::int64_t first = 3 * r_.node_begin, last = 3 * r_.node_end;
    Values(3 * n, type, false, "a point coordinate", [&](std::int64_t i, double v) {
      if (extract && i >= first && i < last) block_.nodes.data()[i - first] = v;
    });
  }

  void Cells(bool extract) {
    cells_line_ = f_.line();
    const std::int64_t n = Count("a number of cells");
    const std::int64_t size = Count("a cell array size");
    if (f_.NextTokenIs("offsets")) {  // the VTK 5.1 layout
      (void)f_.Token("OFFSETS");
      CellsWithOffsets(extract, n, size);
      return;
    }
    if (!extract) num_cells_ = n;
    // Each cell takes at least one value (its point count).
    if (n > size)
      FailIn(
          cells_line_, "CELLS",
          fmt::format("expected at most {} cells in {} values, got a count of {}", size, size, n));
    // A state machine over the values: a cell's point count, then its points.
    std::int64_t cell = 0, left = -1;  // points left of the current cell (-1: expecting a count)
    std::vector<std::int64_t> points;
    const VtkDataType type{4, false, true};
    Values(size, type, true, "a cell entry", [&](std::int64_t i, std::int64_t v) {
      if (left < 0) {
        if (cell == n)
          FailIn(cells_line_, "CELLS",
                 fmt::format("the size {} does not match the {} cells ({} values)", size, n, i));
        if (v < 0 || v > size - i - 1)
          FailIn(cells_line_, "CELLS",
                 fmt::format("cell {} declares {} points, more than the array holds", cell, v));
        left = v;
        points.clear();
      } else {
        points.push_back(v);
        --left;
      }
      if (left == 0) {
        if (extract) Cell(cell, points);
        ++cell;
        left = -1;
      }
    });
    if (cell < n)
      FailIn(
          cells_line_, "CELLS",
          fmt::format("expected {} cells in {} values, but they end after cell {}", n, size, cell));
  }

  // The VTK 5.1 layout: n offsets, then `size` point indices. The second pass takes each tet's
  // and triangle's size from its kind and the others' from `other_sizes_`.
  void CellsWithOffsets(bool extract, std::int64_t n, std::int64_t size) {
    const VtkDataType offset_type = Type();
    std::int64_t previous = 0;
    bool rising = n > 0;
    std::size_t other = 0;
    Values(n, offset_type, true, "an offset", [&](std::int64_t i, std::int64_t v) {
      if ((i == 0 && v != 0) || v < previous) rising = false;
      if (extract && i > 0) {
        const Kind kind = KindOf(i - 1);
        const std::int64_t k = v - previous;
        if (kind != kOther && k != (kind == kTet ? 4 : 3))
          FailIn(cells_line_, "CELLS",
                 fmt::format("expected {} point indices for a {} (cell {}), got {}",
                             kind == kTet ? 4 : 3, kind == kTet ? "tetrahedron" : "triangle", i - 1,
                             k));
        if (kind == kOther) other_sizes_.push_back(k);
      }
      previous = v;
    });
    if (VtkLower(f_.Token("CONNECTIVITY")) != "connectivity")
      f_.Fail("expected CONNECTIVITY after OFFSETS");
    const VtkDataType point_type = Type();
    if (!extract) num_cells_ = std::max<std::int64_t>(n - 1, 0);
    std::int64_t cell = 0, left = -1;
    std::vector<std::int64_t> points;
    const bool checked = rising && previous == size;
    Values(size, point_type, true, "a point index", [&](std::int64_t, std::int64_t v) {
      if (!extract || !checked) return;
      while (left < 0) {  // the next cell's size (cells of no points take none)
        const Kind kind = KindOf(cell);
        left = kind == kTet ? 4 : kind == kTriangle ? 3 : other_sizes_[other++];
        points.clear();
        if (left == 0) {
          ++cell;
          left = -1;
        }
      }
      points.push_back(v);
      if (--left == 0) {
        Cell(cell++, points);
        left = -1;
      }
    });
    if (!checked)
      FailIn(cells_line_, "CELLS",
             fmt::format("expected offsets rising from 0 to the connectivity size {}", size));
  }

  // Checks a tet or triangle as ReadVtkLegacy does and keeps it if it is the block's.
  void Cell(std::int64_t cell, const std::vector<std::int64_t>& points) {
    const Kind kind = KindOf(cell);
    if (kind == kOther) return;
    const int want = kind == kTet ? 4 : 3;
    const auto k = static_cast<std::int64_t>(points.size());
    if (k != want)
      FailIn(cells_line_, "CELLS",
             fmt::format("expected {} point indices for a {} (cell {}), got {}", want,
                         kind == kTet ? "tetrahedron" : "triangle", cell, k));
    int idx[4];
    for (int a = 0; a < want; ++a) {
      const std::int64_t p = points[static_cast<std::size_t>(a)];
      if (p < 0 || p >= num_nodes_)
        FailIn(
            cells_line_, "CELLS",
            fmt::format("cell {} refers to point {}, out of range [0, {})", cell, p, num_nodes_));
      idx[a] = static_cast<int>(p);
    }
    for (int a = 0; a < want; ++a)
      for (int b = 0; b < a; ++b)
        if (idx[a] == idx[b])
          FailIn(cells_line_, "CELLS", fmt::format("cell {} repeats point {}", cell, idx[a]));
    if (kind == kTet) {
      const std::int64_t item = tet_counter_++;
      if (item >= r_.tet_begin && item < r_.tet_end)
        for (int a = 0; a < 4; ++a)
          block_.tets(a, static_cast<Index>(item - r_.tet_begin)) = idx[a];
    } else {
      const std::int64_t item = triangle_counter_++;
      if (item >= r_.triangle_begin && item < r_.triangle_end)
        for (int a = 0; a < 3; ++a)
          block_.triangles(a, static_cast<Index>(item - r_.triangle_begin)) = idx[a];
    }
  }

  void CellTypes(bool extract) {
    const int line = f_.line();
    const std::int64_t n = Count("a number of cell types");
    if (!extract) {
      types_line_ = line;
      num_types_ = n;
      kinds_.assign(static_cast<std::size_t>(std::min<std::int64_t>(n, f_.remaining()) + 3) / 4, 0);
    }
    Values(n, VtkDataType{4, false, true}, true, "a cell type",
           [&](std::int64_t i, std::int64_t type) {
             if (extract) return;
             const Kind kind = type == 10 ? kTet : type == 5 ? kTriangle : kOther;
             kinds_[static_cast<std::size_t>(i / 4)] |=
                 static_cast<std::uint8_t>(kind << (2 * (i % 4)));
             num_tets_ += kind == kTet ? 1 : 0;
             num_triangles_ += kind == kTriangle ? 1 : 0;
           });
  }
  [[nodiscard]] Kind KindOf(std::int64_t cell) const {
    return static_cast<Kind>((kinds_[static_cast<std::size_t>(cell / 4)] >> (2 * (cell % 4))) & 3);
  }

  void SkipMetadata() {
    f_.SkipRestOfLine();
    std::string_view line;
    while (f_.NextLine(&line) && !internal::Trim(line).empty()) {
    }
  }

  void SkipField() {
    (void)f_.Token("a field name");
    const std::int64_t arrays = Count("a number of field arrays");
    for (std::int64_t a = 0; a < arrays; ++a) {
      (void)f_.Token("an array name");
      const std::int64_t components = Count("a number of components");
      const std::int64_t tuples = Count("a number of tuples");
      const VtkDataType type = Type();
      if (components > 0 && tuples > INT64_MAX / components) f_.Fail("field array size overflows");
      const std::int64_t n = components * tuples;
      f_.CheckCount(n, binary_ ? static_cast<std::size_t>(type.bytes) : 1, "field values");
      if (binary_) {
        f_.SkipRestOfLine();
        f_.Skip(static_cast<std::uint64_t>(n * type.bytes), "field values");
      } else {
        for (std::int64_t i = 0; i < n; ++i) (void)f_.Token("a field value");
      }
    }
  }

  ChunkedFile f_;
  int rank_, size_;
  bool binary_ = false;
  // First pass.
  int points_line_ = 0, cells_line_ = 0, types_line_ = 0;
  std::int64_t num_nodes_ = 0, num_cells_ = 0, num_types_ = 0, num_tets_ = 0, num_triangles_ = 0;
  std::vector<std::uint8_t> kinds_;  // 2 bits a cell: Kind
  // Second pass.
  MeshBlock block_;
  std::vector<std::int64_t> other_sizes_;  // VTK 5.1 layout: sizes of the cells of kind kOther
  internal::BlockRanges r_;                // the block's items
  std::int64_t tet_counter_ = 0, triangle_counter_ = 0;
};

}  // namespace

std::optional<MeshBlock> ReadVtkLegacyBlock(const std::filesystem::path& path, int rank, int size) {
  GIPSI_CHECK(size >= 1 && rank >= 0 && rank < size);
  return VtkBlockParser(path, rank, size).Read();
}

}  // namespace gipsi
