#include "gipsi/io/vtu_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <zlib.h>
#include <pugixml.hpp>

#include "gipsi/base/error.h"
#include "gipsi/geometry/edge_key.h"
#include "gipsi/io/base64.h"
#include "gipsi/io/mesh_builder.h"
#include "gipsi/io/text_reader.h"
#include "gipsi/io/vtk_legacy_types.h"
#include "gipsi/io/vtu_markup.h"

namespace gipsi {
namespace {

using internal::LoadScalar;
using internal::Quote;

using internal::kMaxZlibRatio;
using internal::LoadVtkInt;
using internal::LoadVtkReal;

class VtuParser {
 public:
  VtuParser(std::string source, std::string bytes)
      : source_(std::move(source)), bytes_(std::move(bytes)), m_(source_) {
    m_.set_lines(bytes_);
  }

  Mesh Parse() {
    SplitAppendedData();
    pugi::xml_document doc;
    m_.Parse(doc, xml_);
    internal::VtuEncoding encoding;
    pugi::xml_node grid = m_.Grid(doc, &encoding);
    swap_ = encoding.swap;
    compressed_ = encoding.compressed;
    header_bytes_ = encoding.header_bytes;
    int pieces = 0;
    for (pugi::xml_node piece : grid.children("Piece")) {
      ReadPiece(piece);
      ++pieces;
    }
    if (pieces == 0) m_.Fail(grid, "expected at least one <Piece>");
    Mesh mesh = b_.Build(source_);
    mesh.SeparateEdgeNodes(middle_of_edge_);
    return mesh;
  }

 private:
  /// Separates raw appended data (which is not XML) from the XML text.
  void SplitAppendedData() {
    std::size_t app = bytes_.find("<AppendedData");
    if (app == std::string::npos) {
      xml_ = bytes_;
      return;
    }
    std::size_t close = bytes_.find('>', app);
    std::size_t mark = close == std::string::npos ? close : bytes_.find('_', close);
    if (mark == std::string::npos)
      ThrowInputError(source_, fmt::format("line {}", LineOfOffset(app)),
                      "expected '_' starting the <AppendedData> content");
    std::string_view tag(bytes_.data() + app, close - app);
    appended_base64_ = tag.find("encoding=\"base64\"") != std::string_view::npos;
    xml_ = bytes_.substr(0, app) + "</VTKFile>";
    appended_line_ = LineOfOffset(app);
    appended_ = std::string_view(bytes_).substr(mark + 1);
    if (appended_base64_) appended_ = appended_.substr(0, appended_.find('<'));
  }

  int LineOfOffset(std::size_t offset) const { return m_.LineOfOffset(offset); }
  [[noreturn]] void Fail(const pugi::xml_node& node, std::string_view what) const {
    m_.Fail(node, what);
  }
  std::uint64_t Attribute(const pugi::xml_node& node, const char* name) const {
    return m_.Attribute(node, name);
  }

  /// The uncompressed payload of a binary block (header + data), exactly `want` bytes.
  std::string Unpack(const pugi::xml_node& node, std::string_view block, std::uint64_t want) {
    const std::size_t h = static_cast<std::size_t>(header_bytes_);
    auto header = [&](std::size_t i) -> std::uint64_t {
      if ((i + 1) > block.size() / h)
        Fail(node,
             fmt::format("binary data ends inside its header ({} bytes present)", block.size()));
      const char* p = block.data() + i * h;
      return h == 8 ? LoadScalar<std::uint64_t>(p, swap_) : LoadScalar<std::uint32_t>(p, swap_);
    };
    if (!compressed_) {
      std::uint64_t n = header(0);
      if (n != want)
        Fail(node, fmt::format("expected {} bytes of data, the block header says {}", want, n));
      if (n > block.size() - h)
        Fail(node, fmt::format("expected {} bytes of data, only {} present (truncated file?)", n,
                               block.size() - h));
      return std::string(block.substr(h, n));
    }
    std::uint64_t blocks = header(0);
    if (blocks > block.size() / h) Fail(node, "compressed header declares too many blocks");
    std::uint64_t size = header(1), last = header(2);
    if (want > kMaxZlibRatio * block.size() + 1024)
      Fail(node, fmt::format("expected {} bytes of data, more than {} compressed bytes can hold "
                             "(wrong count or truncated file?)",
                             want, block.size()));
    std::uint64_t last_size = last == 0 ? size : last;
    if (blocks > 0 && (size == 0 || last_size > size)) Fail(node, "inconsistent compressed header");
    std::uint64_t total = 0;
    if (blocks > 1 && blocks - 1 > want / size) {
      total = std::numeric_limits<std::uint64_t>::max();
    } else if (blocks > 0) {
      total = (blocks - 1) * size + last_size;
    }
    if (total != want)
      Fail(node,
           fmt::format("expected {} bytes of data, the compressed header says {}", want,
                       total == std::numeric_limits<std::uint64_t>::max() ? std::string("more")
                                                                          : std::to_string(total)));
    std::string out(static_cast<std::size_t>(want), '\0');
    std::size_t pos = h * (3 + std::size_t(blocks));
    std::size_t done = 0;
    for (std::uint64_t b = 0; b < blocks; ++b) {
      std::uint64_t csize = header(3 + std::size_t(b));
      if (pos > block.size() || csize > block.size() - pos)
        Fail(node, fmt::format("compressed block {} is truncated", b));
      uLongf expect = static_cast<uLongf>(b + 1 == blocks ? last_size : size);
      uLongf got = expect;
      int rc =
          uncompress(reinterpret_cast<Bytef*>(out.data() + done), &got,
                     reinterpret_cast<const Bytef*>(block.data() + pos), static_cast<uLong>(csize));
      if (rc != Z_OK || got != expect)
        Fail(node, fmt::format("compressed block {} is corrupt (zlib error {})", b, rc));
      pos += static_cast<std::size_t>(csize);
      done += static_cast<std::size_t>(expect);
    }
    return out;
  }

  /// Reads `count` values of a DataArray as T (double or int64_t). Reals must be finite.
  template <class T>
  std::vector<T> ReadArray(const pugi::xml_node& node, std::uint64_t count) {
    std::string_view type_name = node.attribute("type").value();
    internal::VtkDataType type = internal::ParseVtuDataType(type_name);
    if (type.bytes == 0) Fail(node, fmt::format("unsupported type {}", Quote(type_name)));
    constexpr bool kWantInt = std::is_integral_v<T>;
    if (kWantInt && type.is_float) Fail(node, "expected an integer type");
    std::string_view format = node.attribute("format").value();
    std::vector<T> out;
    if (format == "ascii") {
      auto tokens = internal::SplitTokens(node.text().get());
      if (tokens.size() != count)
        Fail(node, fmt::format("expected {} values, got {}", count, tokens.size()));
      out.reserve(tokens.size());
      for (std::string_view t : tokens) {
        if constexpr (kWantInt) {
          std::int64_t v = 0;
          if (!internal::TryParseInt(t, &v))
            Fail(node, fmt::format("expected an integer, got {}", Quote(t)));
          out.push_back(v);
        } else {
          double v = 0;
          if (!internal::TryParseDouble(t, &v) || !std::isfinite(v))
            Fail(node, fmt::format("expected a finite number, got {}", Quote(t)));
          out.push_back(v);
        }
      }
      return out;
    }
    if (count > std::numeric_limits<std::uint64_t>::max() / 8) Fail(node, "array is too large");
    std::uint64_t want = count * static_cast<std::uint64_t>(type.bytes);
    std::string payload;
    if (format == "binary") {
      std::string_view text = node.text().get();
      std::size_t bad = 0;
      auto decoded = internal::DecodeBase64(text, &bad);
      if (!decoded) Fail(node, fmt::format("invalid base64 at character {}", bad));
      payload = Unpack(node, *decoded, want);
    } else if (format == "appended") {
      std::uint64_t offset = Attribute(node, "offset");
      if (offset > appended_.size())
        Fail(node, fmt::format("offset {} is beyond the appended data ({} bytes, line {})", offset,
                               appended_.size(), appended_line_));
      if (appended_base64_) {
        std::size_t bad = 0;
        auto decoded = internal::DecodeBase64(appended_.substr(offset), &bad);
        if (!decoded) Fail(node, fmt::format("invalid base64 in AppendedData at {}", offset + bad));
        payload = Unpack(node, *decoded, want);
      } else {
        payload = Unpack(node, appended_.substr(offset), want);
      }
    } else {
      Fail(node, fmt::format("expected format ascii, binary or appended, got {}", Quote(format)));
    }
    out.resize(static_cast<std::size_t>(count));
    const char* p = payload.data();
    for (std::size_t i = 0; i < out.size(); ++i, p += type.bytes) {
      if (type.is_float) {
        double v = LoadVtkReal(p, type, swap_);
        if (!std::isfinite(v)) Fail(node, fmt::format("value {} is not finite", i));
        out[i] = static_cast<T>(v);
        continue;
      }
      std::int64_t v = LoadVtkInt(p, type, swap_);
      out[i] = static_cast<T>(v);
    }
    return out;
  }

  void ReadPiece(const pugi::xml_node& piece) {
    std::uint64_t num_points = Attribute(piece, "NumberOfPoints");
    std::uint64_t num_cells = Attribute(piece, "NumberOfCells");
    if (num_points > static_cast<std::uint64_t>(std::numeric_limits<int>::max() - b_.num_nodes()))
      Fail(piece, "too many points");
    const int base = b_.num_nodes();
    pugi::xml_node points = m_.PointsArray(piece);
    std::vector<double> xyz = ReadArray<double>(points, 3 * num_points);
    b_.coords.insert(b_.coords.end(), xyz.begin(), xyz.end());
    if (num_cells == 0) return;
    pugi::xml_node cells = piece.child("Cells");
    if (!cells) Fail(piece, "expected a <Cells> element");
    pugi::xml_node offsets_node = m_.FindArray(cells, "offsets");
    pugi::xml_node types_node = m_.FindArray(cells, "types");
    pugi::xml_node conn_node = m_.FindArray(cells, "connectivity");
    auto offsets = ReadArray<std::int64_t>(offsets_node, num_cells);
    auto types = ReadArray<std::int64_t>(types_node, num_cells);
    std::int64_t previous = 0;
    for (std::size_t c = 0; c < offsets.size(); ++c) {
      if (offsets[c] < previous)
        Fail(offsets_node,
             fmt::format("offset {} of cell {} is below the previous {}", offsets[c], c, previous));
      previous = offsets[c];
    }
    auto conn = ReadArray<std::int64_t>(conn_node, static_cast<std::uint64_t>(offsets.back()));
    for (std::size_t c = 0; c < offsets.size(); ++c) {
      std::int64_t begin = c == 0 ? 0 : offsets[c - 1];
      std::int64_t k = offsets[c] - begin;
      const std::int64_t type = types[c];
      const bool tet = type == 10 || type == 24;
      if (!tet && type != 5 && type != 22) continue;
      const std::int64_t want = type == 10 ? 4 : type == 5 ? 3 : type == 24 ? 10 : 6;
      const char* name = type == 10   ? "tetrahedron"
                         : type == 5  ? "triangle"
                         : type == 24 ? "quadratic tetrahedron"
                                      : "quadratic triangle";
      if (k != want)
        Fail(conn_node,
             fmt::format("expected {} point indices for a {} (cell {}), got {}", want, name, c, k));
      int idx[10];
      for (std::int64_t a = 0; a < k; ++a) {
        std::int64_t p = conn[std::size_t(begin + a)];
        if (p < 0 || static_cast<std::uint64_t>(p) >= num_points)
          Fail(conn_node,
               fmt::format("cell {} refers to point {}, out of range [0, {})", c, p, num_points));
        idx[a] = base + static_cast<int>(p);
        for (std::int64_t c2 = 0; c2 < a; ++c2)
          if (idx[c2] == idx[a]) Fail(conn_node, fmt::format("cell {} repeats point {}", c, p));
      }
      if (tet)
        b_.AddTet(idx[0], idx[1], idx[2], idx[3]);
      else
        b_.AddTriangle(idx[0], idx[1], idx[2]);
      // VTK's quadratic cells: after the corners, the middle nodes of the edges (0,1), (1,2),
      // (0,2), then for tets (0,3), (1,3), (2,3).
      static constexpr int kEdges[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
      const int corners = tet ? 4 : 3;
      for (int e = 0; e + corners < k; ++e) {
        const int a = idx[kEdges[e][0]], b = idx[kEdges[e][1]];
        const auto [it, inserted] = middle_of_edge_.emplace(EdgeKey(a, b), idx[corners + e]);
        if (!inserted && it->second != idx[corners + e])
          Fail(conn_node, fmt::format("cell {} puts point {} in the middle of an edge where "
                                      "another cell has point {}: the quadratic cells do not "
                                      "conform",
                                      c, idx[corners + e] - base, it->second - base));
      }
    }
  }

  std::string source_;
  std::string bytes_;
  internal::VtuMarkup m_;  // messages: lines counted in bytes_
  std::string xml_;
  std::string_view appended_;
  bool appended_base64_ = false;
  int appended_line_ = 0;
  bool swap_ = false;
  bool compressed_ = false;
  int header_bytes_ = 4;
  internal::MeshBuilder b_;
  std::map<std::uint64_t, int> middle_of_edge_;  // quadratic cells' edges -> middle point
};

}  // namespace

Mesh ReadVtu(const std::filesystem::path& path) {
  return VtuParser(path.string(), internal::ReadFileBytes(path)).Parse();
}

}  // namespace gipsi
