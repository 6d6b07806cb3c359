#include "gipsi/io/tetgen_reader.h"

#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/io/mesh_builder.h"
#include "gipsi/io/text_reader.h"

namespace gipsi {
namespace {

using internal::SplitTokens;
using internal::TextReader;

/// The tokens of the next content line (comments stripped), at least `min_tokens` of them.
std::vector<std::string_view> ReadRecord(TextReader& r, std::size_t min_tokens,
                                         std::string_view what) {
  auto t = SplitTokens(r.RequireContentLine(what, '#'));
  if (t.size() < min_tokens)
    r.Fail(fmt::format("expected {} with {} values, got {}", what, min_tokens, t.size()));
  return t;
}

/// A header value or `fallback` when the header is shorter.
std::int64_t HeaderValue(TextReader& r, const std::vector<std::string_view>& t, std::size_t i,
                         std::int64_t fallback, std::string_view what) {
  if (i >= t.size()) return fallback;
  std::int64_t v = r.ToInt(t[i], what);
  if (v < 0) r.Fail(fmt::format("expected {} (non-negative), got {}", what, v));
  return v;
}

/// A group name suffix for an attribute or marker value: integers without decimals.
std::string ValueName(double v) {
  if (v == std::floor(v) && std::abs(v) < 1e15) return fmt::format("{}", std::int64_t(v));
  return fmt::format("{}", v);
}

class TetGenParser {
 public:
  Mesh Parse(const std::filesystem::path& stem) {
    std::filesystem::path face = std::filesystem::path(stem).concat(".face");
    ReadNodes(std::filesystem::path(stem).concat(".node"));
    ReadEle(std::filesystem::path(stem).concat(".ele"));
    if (std::filesystem::exists(face)) ReadFaces(face);
    for (auto& [value, items] : regions_)
      b_.groups.push_back({fmt::format("region_{}", ValueName(value)), 3, std::move(items)});
    for (auto& [value, items] : markers_)
      b_.groups.push_back({fmt::format("marker_{}", value), 2, std::move(items)});
    return b_.Build(source_);
  }

 private:
  int Node(TextReader& r, std::string_view token) {
    std::int64_t number = r.ToInt(token, "a node number");
    int i = nodes_.Find(number);
    if (i < 0) r.Fail(fmt::format("refers to undefined node {}", number));
    return i;
  }

  void ReadNodes(const std::filesystem::path& path) {
    TextReader r = TextReader::FromFile(path);
    source_ = r.source();
    auto h = ReadRecord(r, 1, "the header '<#points> <dim> <#attributes> <#markers>'");
    std::int64_t n = HeaderValue(r, h, 0, 0, "a number of points");
    std::int64_t dim = HeaderValue(r, h, 1, 3, "a dimension");
    std::int64_t attributes = HeaderValue(r, h, 2, 0, "a number of attributes");
    std::int64_t markers = HeaderValue(r, h, 3, 0, "a number of boundary markers");
    if (dim != 3) r.Fail(fmt::format("expected dimension 3, got {}", dim));
    if (markers > 1) r.Fail(fmt::format("expected 0 or 1 boundary markers, got {}", markers));
    r.CheckCount(n, 8, "points");
    nodes_.Reserve(static_cast<std::size_t>(n));
    b_.coords.reserve(static_cast<std::size_t>(3 * n));
    std::size_t want = static_cast<std::size_t>(4 + attributes + markers);
    for (std::int64_t i = 0; i < n; ++i) {
      auto t = ReadRecord(r, want, "a point line '<#> <x> <y> <z> [attributes] [marker]'");
      std::int64_t number = r.ToInt(t[0], "a point number");
      if (!nodes_.Insert(number)) r.Fail(fmt::format("point {} is defined twice", number));
      b_.AddNode(r.ToFinite(t[1], "an x coordinate"), r.ToFinite(t[2], "a y coordinate"),
                 r.ToFinite(t[3], "a z coordinate"));
    }
  }

  void ReadEle(const std::filesystem::path& path) {
    TextReader r = TextReader::FromFile(path);
    auto h = ReadRecord(r, 1, "the header '<#tetrahedra> <nodes per tet> <#attributes>'");
    std::int64_t n = HeaderValue(r, h, 0, 0, "a number of tetrahedra");
    std::int64_t per = HeaderValue(r, h, 1, 4, "a number of nodes per tetrahedron");
    std::int64_t attributes = HeaderValue(r, h, 2, 0, "a number of attributes");
    if (per != 4 && per != 10) r.Fail(fmt::format("expected 4 or 10 nodes per tet, got {}", per));
    r.CheckCount(n, 10, "tetrahedra");
    b_.tets.reserve(static_cast<std::size_t>(4 * n));
    std::size_t want = static_cast<std::size_t>(1 + per + attributes);
    for (std::int64_t i = 0; i < n; ++i) {
      auto t = SplitTokens(r.RequireContentLine("a tetrahedron line", '#'));
      if (t.size() < want)
        r.Fail(
            fmt::format("expected {} node indices and {} attributes for a tetrahedron, got {} "
                        "values",
                        per, attributes, t.size() - 1));
      int tet = b_.AddTet(Node(r, t[1]), Node(r, t[2]), Node(r, t[3]), Node(r, t[4]));
      for (int a = 0; a < 4; ++a)
        for (int c = 0; c < a; ++c)
          if (b_.tets[std::size_t(4 * tet + a)] == b_.tets[std::size_t(4 * tet + c)])
            r.Fail(fmt::format("tetrahedron {} repeats node {}", t[0], t[std::size_t(a) + 1]));
      if (attributes > 0)
        regions_[r.ToFinite(t[std::size_t(1 + per)], "a region attribute")].push_back(tet);
    }
  }

  void ReadFaces(const std::filesystem::path& path) {
    TextReader r = TextReader::FromFile(path);
    auto h = ReadRecord(r, 1, "the header '<#faces> <#markers>'");
    std::int64_t n = HeaderValue(r, h, 0, 0, "a number of faces");
    std::int64_t markers = HeaderValue(r, h, 1, 0, "a number of boundary markers");
    if (markers > 1) r.Fail(fmt::format("expected 0 or 1 boundary markers, got {}", markers));
    r.CheckCount(n, 8, "faces");
    b_.triangles.reserve(static_cast<std::size_t>(3 * n));
    for (std::int64_t i = 0; i < n; ++i) {
      auto t = SplitTokens(r.RequireContentLine("a face line", '#'));
      if (t.size() < std::size_t(4 + markers))
        r.Fail(fmt::format("expected 3 node indices{} for a face, got {} values",
                           markers ? " and a marker" : "", t.size() - 1));
      int a = Node(r, t[1]), b = Node(r, t[2]), c = Node(r, t[3]);
      if (a == b || b == c || a == c) r.Fail(fmt::format("face {} repeats a node", t[0]));
      int tri = b_.AddTriangle(a, b, c);
      if (markers > 0) markers_[r.ToInt(t[4], "a boundary marker")].push_back(tri);
    }
  }

  std::string source_;
  internal::MeshBuilder b_;
  internal::TagMap nodes_;
  std::map<double, std::vector<int>> regions_;
  std::map<std::int64_t, std::vector<int>> markers_;
};

}  // namespace

Mesh ReadTetGen(const std::filesystem::path& path) {
  std::filesystem::path stem = path;
  stem.replace_extension();
  return TetGenParser().Parse(stem);
}

}  // namespace gipsi
