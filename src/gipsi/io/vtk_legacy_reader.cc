#include "gipsi/io/vtk_legacy_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/io/mesh_builder.h"
#include "gipsi/io/text_reader.h"
#include "gipsi/io/vtk_legacy_types.h"

namespace gipsi {
namespace {

using internal::Quote;
using internal::TextReader;

using DataType = internal::VtkDataType;

std::string Lower(std::string_view s) { return internal::VtkLower(s); }
DataType ParseDataType(std::string_view name) { return internal::ParseVtkDataType(name); }

/// Cells as offsets (size n+1) into a connectivity array, plus where they were declared.
struct CellArray {
  std::vector<std::int64_t> offsets{0};
  std::vector<std::int64_t> conn;
  int line = 0;
  std::string keyword;
};

class VtkLegacyParser {
 public:
  explicit VtkLegacyParser(TextReader& r) : r_(r) {}

  Mesh Parse() {
    ReadHeader();
    for (std::string_view token = r_.NextToken(); !token.empty(); token = r_.NextToken()) {
      std::string key = Lower(token);
      if (key == "points") {
        ReadPoints();
      } else if (key == "cells" && grid_) {
        cells_ = ReadCellArray("CELLS");
      } else if (key == "cell_types" && grid_) {
        ReadCellTypes();
      } else if (!grid_ && (key == "polygons" || key == "triangle_strips" || key == "vertices" ||
                            key == "lines")) {
        CellArray cells = ReadCellArray(std::string(token));
        if (key == "polygons") polygons_ = std::move(cells);
        if (key == "triangle_strips") strips_ = std::move(cells);
      } else if (key == "metadata") {
        SkipMetadata();
      } else if (key == "field") {
        SkipField();
      } else if (key == "point_data" || key == "cell_data") {
        break;
      } else {
        std::string what =
            fmt::format("expected a section keyword ({}), got {}",
                        grid_ ? "POINTS, CELLS, CELL_TYPES, POINT_DATA or CELL_DATA"
                              : "POINTS, POLYGONS, TRIANGLE_STRIPS, POINT_DATA or CELL_DATA",
                        Quote(token));
        if (!binary_) r_.Fail(what);
        ThrowInputError(
            r_.source(),
            fmt::format("line {} (byte offset {})", r_.line(), r_.offset() - token.size()),
            what + "; the binary data before it does not match its declared count");
      }
    }
    if (points_line_ == 0) r_.Fail("expected a POINTS section, got end of file");
    BuildCells();
    return b_.Build(r_.source());
  }

 private:
  [[noreturn]] void FailIn(int line, std::string_view section, std::string_view what) const {
    ThrowInputError(r_.source(), fmt::format("line {} ({})", line, section), what);
  }

  void ReadHeader() {
    std::string_view line;
    if (!r_.NextLine(&line) || line.rfind("# vtk DataFile Version", 0) != 0)
      r_.Fail(fmt::format("expected '# vtk DataFile Version x.x', got {}", Quote(line)));
    if (!r_.NextLine(&line)) r_.Fail("expected a title line, got end of file");
    std::string format = Lower(internal::Trim(r_.RequireContentLine("ASCII or BINARY")));
    if (format != "ascii" && format != "binary")
      r_.Fail(fmt::format("expected ASCII or BINARY, got {}", Quote(format)));
    binary_ = format == "binary";
    auto t = internal::SplitTokens(r_.RequireContentLine("DATASET <type>"));
    if (t.size() != 2 || Lower(t[0]) != "dataset")
      r_.Fail("expected 'DATASET UNSTRUCTURED_GRID' or 'DATASET POLYDATA'");
    std::string kind = Lower(t[1]);
    if (kind != "unstructured_grid" && kind != "polydata")
      r_.Fail(fmt::format("unsupported dataset {} (supported: UNSTRUCTURED_GRID, POLYDATA)",
                          Quote(t[1])));
    grid_ = kind == "unstructured_grid";
  }

  std::int64_t ReadCount(std::string_view what) {
    std::int64_t n = r_.ReadInt(what);
    if (n < 0) r_.Fail(fmt::format("expected {} (non-negative), got {}", what, n));
    return n;
  }

  DataType ReadType() {
    std::string_view name = r_.RequireToken("a data type");
    DataType type = ParseDataType(name);
    if (type.bytes == 0) r_.Fail(fmt::format("unsupported data type {}", Quote(name)));
    return type;
  }

  /// Reads `n` numbers of `type` (ASCII tokens or big-endian binary) after the header line.
  /// Each value goes through `sink(i, value)`; integers are exact, reals are checked finite.
  template <class Sink>
  void ReadValues(std::int64_t n, DataType type, bool want_int, std::string_view what, Sink sink) {
    if (want_int && type.is_float) r_.Fail(fmt::format("expected an integer type for {}", what));
    if (!binary_) {
      r_.CheckCount(n, 1, what);
      for (std::int64_t i = 0; i < n; ++i) {
        if (want_int)
          sink(i, r_.ReadInt(what));
        else
          sink(i, r_.ReadFinite(what));
      }
      return;
    }
    r_.SkipRestOfLine();
    r_.CheckCount(n, static_cast<std::size_t>(type.bytes), what);
    const bool swap = internal::HostIsLittleEndian();
    std::size_t start = r_.offset();
    const char* p = r_.ReadBytes(static_cast<std::size_t>(n * type.bytes), what).data();
    for (std::int64_t i = 0; i < n; ++i, p += type.bytes) {
      if (type.is_float) {
        const double v = internal::LoadVtkReal(p, type, swap);
        if (!std::isfinite(v))
          r_.FailAtOffset(fmt::format("expected {} (a finite number), got {}", what, v),
                          start + static_cast<std::size_t>(i * type.bytes));
        sink(i, v);
        continue;
      }
      const std::int64_t v = internal::LoadVtkInt(p, type, swap);
      sink(i, v);
    }
  }

  std::vector<std::int64_t> ReadInts(std::int64_t n, DataType type, std::string_view what) {
    std::vector<std::int64_t> out;
    ReadValues(n, type, true, what,
               [&](std::int64_t, auto v) { out.push_back(static_cast<std::int64_t>(v)); });
    return out;
  }

  void ReadPoints() {
    if (points_line_ != 0) r_.Fail("a second POINTS section");
    points_line_ = r_.line();
    std::int64_t n = ReadCount("a number of points");
    DataType type = ReadType();
    if (!type.is_float) r_.Fail("expected a real data type (float or double) for POINTS");
    r_.CheckCount(n, 3, "points");
    b_.coords.resize(static_cast<std::size_t>(3 * n));
    ReadValues(3 * n, type, false, "a point coordinate", [&](std::int64_t i, auto v) {
      b_.coords[static_cast<std::size_t>(i)] = static_cast<double>(v);
    });
  }

  CellArray ReadCellArray(std::string keyword) {
    CellArray cells;
    cells.line = r_.line();
    cells.keyword = std::move(keyword);
    std::int64_t n = ReadCount("a number of cells");
    std::int64_t size = ReadCount("a cell array size");
    if (Lower(r_.PeekToken()) == "offsets") {  // VTK 5.1 layout
      r_.NextToken();
      cells.offsets = ReadInts(n, ReadType(), "an offset");
      if (Lower(r_.RequireToken("CONNECTIVITY")) != "connectivity")
        r_.Fail("expected CONNECTIVITY after OFFSETS");
      cells.conn = ReadInts(size, ReadType(), "a point index");
      if (cells.offsets.empty() || cells.offsets.front() != 0 ||
          cells.offsets.back() != static_cast<std::int64_t>(cells.conn.size()) ||
          !std::is_sorted(cells.offsets.begin(), cells.offsets.end()))
        FailIn(cells.line, cells.keyword,
               fmt::format("expected offsets rising from 0 to the connectivity size {}", size));
      return cells;
    }
    std::vector<std::int64_t> data = ReadInts(size, DataType{4, false, true}, "a cell entry");
    // Each cell takes at least one value (its point count), so a larger count cannot be true;
    // checked before it sizes any allocation.
    if (static_cast<std::uint64_t>(n) > data.size())
      FailIn(cells.line, cells.keyword,
             fmt::format("expected at most {} cells in {} values, got a count of {}", data.size(),
                         size, n));
    std::size_t pos = 0;
    cells.offsets.reserve(static_cast<std::size_t>(n) + 1);
    for (std::int64_t c = 0; c < n; ++c) {
      if (pos >= data.size())
        FailIn(
            cells.line, cells.keyword,
            fmt::format("expected {} cells in {} values, but they end after cell {}", n, size, c));
      std::int64_t k = data[pos];
      if (k < 0 || static_cast<std::uint64_t>(k) > data.size() - pos - 1)
        FailIn(cells.line, cells.keyword,
               fmt::format("cell {} declares {} points, more than the array holds", c, k));
      cells.conn.insert(cells.conn.end(), data.begin() + std::ptrdiff_t(pos + 1),
                        data.begin() + std::ptrdiff_t(pos + 1 + std::size_t(k)));
      cells.offsets.push_back(static_cast<std::int64_t>(cells.conn.size()));
      pos += 1 + static_cast<std::size_t>(k);
    }
    if (pos != data.size())
      FailIn(cells.line, cells.keyword,
             fmt::format("the size {} does not match the {} cells ({} values)", size, n, pos));
    return cells;
  }

  void ReadCellTypes() {
    types_line_ = r_.line();
    std::int64_t n = ReadCount("a number of cell types");
    types_ = ReadInts(n, DataType{4, false, true}, "a cell type");
  }

  void SkipMetadata() {
    r_.SkipRestOfLine();
    std::string_view line;
    while (r_.NextLine(&line) && !internal::Trim(line).empty()) {
    }
  }

  void SkipField() {
    r_.RequireToken("a field name");
    std::int64_t arrays = ReadCount("a number of field arrays");
    for (std::int64_t a = 0; a < arrays; ++a) {
      r_.RequireToken("an array name");
      std::int64_t components = ReadCount("a number of components");
      std::int64_t tuples = ReadCount("a number of tuples");
      DataType type = ReadType();
      if (components > 0 && tuples > INT64_MAX / components) r_.Fail("field array size overflows");
      std::int64_t n = components * tuples;
      r_.CheckCount(n, binary_ ? std::size_t(type.bytes) : 1, "field values");
      if (binary_) {
        r_.SkipRestOfLine();
        r_.ReadBytes(static_cast<std::size_t>(n * type.bytes), "field values");
      } else {
        for (std::int64_t i = 0; i < n; ++i) r_.RequireToken("a field value");
      }
    }
  }

  int PointIndex(const CellArray& cells, std::int64_t c, std::int64_t p) const {
    if (p < 0 || p >= b_.num_nodes())
      FailIn(cells.line, cells.keyword,
             fmt::format("cell {} refers to point {}, out of range [0, {})", c, p, b_.num_nodes()));
    return static_cast<int>(p);
  }

  void AddTriangle(int a, int b, int c) {
    if (a != b && b != c && a != c) b_.AddTriangle(a, b, c);
  }

  void BuildCells() {
    if (grid_) {
      std::int64_t n = static_cast<std::int64_t>(cells_.offsets.size()) - 1;
      if (n > 0 && types_line_ == 0) r_.Fail("expected a CELL_TYPES section, got end of file");
      if (types_line_ != 0 && static_cast<std::int64_t>(types_.size()) != n)
        FailIn(types_line_, "CELL_TYPES",
               fmt::format("expected {} cell types (one per cell), got {}", n, types_.size()));
      for (std::int64_t c = 0; c < n; ++c) {
        const std::int64_t* v = cells_.conn.data() + cells_.offsets[std::size_t(c)];
        std::int64_t k = cells_.offsets[std::size_t(c) + 1] - cells_.offsets[std::size_t(c)];
        std::int64_t type = types_[std::size_t(c)];
        if (type != 10 && type != 5) continue;
        std::int64_t want = type == 10 ? 4 : 3;
        if (k != want)
          FailIn(cells_.line, cells_.keyword,
                 fmt::format("expected {} point indices for a {} (cell {}), got {}", want,
                             type == 10 ? "tetrahedron" : "triangle", c, k));
        int idx[4];
        for (int a = 0; a < k; ++a) idx[a] = PointIndex(cells_, c, v[a]);
        for (int a = 0; a < k; ++a)
          for (int b = 0; b < a; ++b)
            if (idx[a] == idx[b])
              FailIn(cells_.line, cells_.keyword,
                     fmt::format("cell {} repeats point {}", c, idx[a]));
        if (type == 10)
          b_.AddTet(idx[0], idx[1], idx[2], idx[3]);
        else
          b_.AddTriangle(idx[0], idx[1], idx[2]);
      }
      return;
    }
    for (const CellArray* cells : {&polygons_, &strips_}) {
      bool strip = cells == &strips_;
      for (std::size_t c = 0; c + 1 < cells->offsets.size(); ++c) {
        std::int64_t begin = cells->offsets[c], end = cells->offsets[c + 1];
        auto at = [&](std::int64_t i) {
          return PointIndex(*cells, std::int64_t(c), cells->conn[std::size_t(i)]);
        };
        for (std::int64_t i = begin; i + 2 < end; ++i) {
          if (!strip)
            AddTriangle(at(begin), at(i + 1), at(i + 2));
          else if ((i - begin) % 2 == 0)
            AddTriangle(at(i), at(i + 1), at(i + 2));
          else
            AddTriangle(at(i + 1), at(i), at(i + 2));
        }
      }
    }
  }

  TextReader& r_;
  bool binary_ = false;
  bool grid_ = false;
  int points_line_ = 0;
  int types_line_ = 0;
  CellArray cells_, polygons_, strips_;
  std::vector<std::int64_t> types_;
  internal::MeshBuilder b_;
};

}  // namespace

Mesh ReadVtkLegacy(const std::filesystem::path& path) {
  TextReader reader = TextReader::FromFile(path);
  return VtkLegacyParser(reader).Parse();
}

}  // namespace gipsi
