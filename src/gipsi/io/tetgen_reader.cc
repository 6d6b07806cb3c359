/// @file
/// TetGen `.node` / `.ele` / `.face` files, streamed in one pass each (see the header).

#include "gipsi/io/tetgen_reader.h"

#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/io/chunked_file.h"
#include "gipsi/io/text_reader.h"

namespace gipsi {
namespace {

using internal::ChunkedFile;
using internal::SplitTokens;

/// The tokens of the next content line (comments stripped), at least `min_tokens` of them.
std::vector<std::string_view> ReadRecord(ChunkedFile& r, std::size_t min_tokens,
                                         std::string_view what) {
  auto t = SplitTokens(r.RequireContentLine(what, '#'));
  if (t.size() < min_tokens)
    r.Fail(fmt::format("expected {} with {} values, got {}", what, min_tokens, t.size()));
  return t;
}

/// A header value or `fallback` when the header is shorter.
std::int64_t HeaderValue(const ChunkedFile& r, const std::vector<std::string_view>& t,
                         std::size_t i, std::int64_t fallback, std::string_view what) {
  if (i >= t.size()) return fallback;
  std::int64_t v = r.ToInt(t[i], what);
  if (v < 0) r.Fail(fmt::format("expected {} (non-negative), got {}", what, v));
  return v;
}

/// The most attributes a line may declare: a line's token count is added to it, which must not
/// overflow (a header of 2^63 - 1 attributes would), and no mesh has a million per item.
constexpr std::int64_t kMostAttributes = 1000000;

/// The header's number of attributes (index `i`), at most kMostAttributes.
std::int64_t Attributes(const ChunkedFile& r, const std::vector<std::string_view>& t,
                        std::size_t i) {
  const std::int64_t v = HeaderValue(r, t, i, 0, "a number of attributes");
  if (v > kMostAttributes)
    r.Fail(fmt::format("expected a number of attributes up to {}, got {}", kMostAttributes, v));
  return v;
}

/// A group name suffix for an attribute or marker value: integers without decimals.
std::string ValueName(double v) {
  if (v == std::floor(v) && std::abs(v) < 1e15) return fmt::format("{}", std::int64_t(v));
  return fmt::format("{}", v);
}

/// The index of each node number, in file order: a run of consecutive numbers needs no table
/// (the usual file, numbered from 0 or 1); other numbers are kept in one (16 bytes per node).
class NodeNumbers {
 public:
  /// Adds `number` as the next index; false if it was already there.
  bool Insert(std::int64_t number) {
    if (consecutive_) {
      if (count_ == 0) first_ = number;
      if (number == first_ + count_) {
        ++count_;
        return true;
      }
      consecutive_ = false;
      table_.Reserve(static_cast<std::size_t>(count_) + 1);
      for (std::int64_t k = 0; k < count_; ++k) (void)table_.Insert(first_ + k);
    }
    return table_.Insert(number);
  }
  /// The index of `number`, or -1.
  [[nodiscard]] int Find(std::int64_t number) const {
    if (!consecutive_) return table_.Find(number);
    return number >= first_ && number - first_ < count_ ? static_cast<int>(number - first_) : -1;
  }

 private:
  bool consecutive_ = true;
  std::int64_t first_ = 0, count_ = 0;
  internal::TagMap table_;
};

/// Reads rank `rank`'s block of `size` of the files with stem `stem`: every line is read and
/// checked, the block's items kept.
class TetGenParser {
 public:
  TetGenParser(int rank, int size) : rank_(rank), size_(size) {
    block_.rank = rank;
    block_.size = size;
  }

  MeshBlock Parse(const std::filesystem::path& stem) {
    std::filesystem::path face = std::filesystem::path(stem).concat(".face");
    ReadNodes(std::filesystem::path(stem).concat(".node"));
    ReadEle(std::filesystem::path(stem).concat(".ele"));
    if (std::filesystem::exists(face)) ReadFaces(face);
    for (auto& [value, items] : regions_)
      block_.groups.push_back({fmt::format("region_{}", ValueName(value)), 3, std::move(items)});
    for (auto& [value, items] : markers_)
      block_.groups.push_back({fmt::format("marker_{}", value), 2, std::move(items)});
    return std::move(block_);
  }
  [[nodiscard]] const std::string& source() const { return source_; }

 private:
  // The block [begin, end) of `count` items.
  [[nodiscard]] std::pair<std::int64_t, std::int64_t> Block(std::int64_t count) const {
    return {BlockBegin(count, rank_, size_), BlockBegin(count, rank_ + 1, size_)};
  }

  int Node(const ChunkedFile& r, std::string_view token) const {
    std::int64_t number = r.ToInt(token, "a node number");
    int i = nodes_.Find(number);
    if (i < 0) r.Fail(fmt::format("refers to undefined node {}", number));
    return i;
  }

  void ReadNodes(const std::filesystem::path& path) {
    ChunkedFile r(path);
    source_ = r.source();
    auto h = ReadRecord(r, 1, "the header '<#points> <dim> <#attributes> <#markers>'");
    std::int64_t n = HeaderValue(r, h, 0, 0, "a number of points");
    std::int64_t dim = HeaderValue(r, h, 1, 3, "a dimension");
    std::int64_t attributes = Attributes(r, h, 2);
    std::int64_t markers = HeaderValue(r, h, 3, 0, "a number of boundary markers");
    if (dim != 3) r.Fail(fmt::format("expected dimension 3, got {}", dim));
    if (markers > 1) r.Fail(fmt::format("expected 0 or 1 boundary markers, got {}", markers));
    r.CheckCount(n, 8, "points");
    const auto [begin, end] = Block(n);
    block_.num_nodes = n;
    block_.nodes.resize(3, static_cast<Index>(end - begin));
    std::size_t want = static_cast<std::size_t>(4 + attributes + markers);
    for (std::int64_t i = 0; i < n; ++i) {
      auto t = ReadRecord(r, want, "a point line '<#> <x> <y> <z> [attributes] [marker]'");
      std::int64_t number = r.ToInt(t[0], "a point number");
      if (!nodes_.Insert(number)) r.Fail(fmt::format("point {} is defined twice", number));
      const Vec3 x(r.ToFinite(t[1], "an x coordinate"), r.ToFinite(t[2], "a y coordinate"),
                   r.ToFinite(t[3], "a z coordinate"));
      if (i >= begin && i < end) block_.nodes.col(static_cast<Index>(i - begin)) = x;
    }
  }

  void ReadEle(const std::filesystem::path& path) {
    ChunkedFile r(path);
    auto h = ReadRecord(r, 1, "the header '<#tetrahedra> <nodes per tet> <#attributes>'");
    std::int64_t n = HeaderValue(r, h, 0, 0, "a number of tetrahedra");
    std::int64_t per = HeaderValue(r, h, 1, 4, "a number of nodes per tetrahedron");
    std::int64_t attributes = Attributes(r, h, 2);
    if (per != 4 && per != 10) r.Fail(fmt::format("expected 4 or 10 nodes per tet, got {}", per));
    r.CheckCount(n, 10, "tetrahedra");
    const auto [begin, end] = Block(n);
    block_.num_tets = n;
    block_.tets.resize(4, static_cast<Index>(end - begin));
    std::size_t want = static_cast<std::size_t>(1 + per + attributes);
    for (std::int64_t i = 0; i < n; ++i) {
      auto t = SplitTokens(r.RequireContentLine("a tetrahedron line", '#'));
      if (t.size() < want)
        r.Fail(
            fmt::format("expected {} node indices and {} attributes for a tetrahedron, got {} "
                        "values",
                        per, attributes, t.size() - 1));
      const Eigen::Vector4i tet(Node(r, t[1]), Node(r, t[2]), Node(r, t[3]), Node(r, t[4]));
      for (int a = 0; a < 4; ++a)
        for (int c = 0; c < a; ++c)
          if (tet[a] == tet[c])
            r.Fail(fmt::format("tetrahedron {} repeats node {}", t[0], t[std::size_t(a) + 1]));
      const bool mine = i >= begin && i < end;
      if (mine) block_.tets.col(static_cast<Index>(i - begin)) = tet;
      if (attributes > 0) {
        std::vector<int>& items =
            regions_[r.ToFinite(t[std::size_t(1 + per)], "a region attribute")];
        if (mine) items.push_back(static_cast<int>(i));
      }
    }
  }

  void ReadFaces(const std::filesystem::path& path) {
    ChunkedFile r(path);
    auto h = ReadRecord(r, 1, "the header '<#faces> <#markers>'");
    std::int64_t n = HeaderValue(r, h, 0, 0, "a number of faces");
    std::int64_t markers = HeaderValue(r, h, 1, 0, "a number of boundary markers");
    if (markers > 1) r.Fail(fmt::format("expected 0 or 1 boundary markers, got {}", markers));
    r.CheckCount(n, 8, "faces");
    const auto [begin, end] = Block(n);
    block_.num_triangles = n;
    block_.first_triangle = begin;
    block_.triangles.resize(3, static_cast<Index>(end - begin));
    for (std::int64_t i = 0; i < n; ++i) {
      auto t = SplitTokens(r.RequireContentLine("a face line", '#'));
      if (t.size() < std::size_t(4 + markers))
        r.Fail(fmt::format("expected 3 node indices{} for a face, got {} values",
                           markers ? " and a marker" : "", t.size() - 1));
      int a = Node(r, t[1]), b = Node(r, t[2]), c = Node(r, t[3]);
      if (a == b || b == c || a == c) r.Fail(fmt::format("face {} repeats a node", t[0]));
      const bool mine = i >= begin && i < end;
      if (mine) block_.triangles.col(static_cast<Index>(i - begin)) = Eigen::Vector3i(a, b, c);
      if (markers > 0) {
        std::vector<int>& items = markers_[r.ToInt(t[4], "a boundary marker")];
        if (mine) items.push_back(static_cast<int>(i));
      }
    }
  }

  int rank_ = 0, size_ = 1;
  std::string source_;
  MeshBlock block_;
  NodeNumbers nodes_;
  std::map<double, std::vector<int>> regions_;
  std::map<std::int64_t, std::vector<int>> markers_;
};

std::filesystem::path Stem(const std::filesystem::path& path) {
  std::filesystem::path stem = path;
  stem.replace_extension();
  return stem;
}

}  // namespace

Mesh ReadTetGen(const std::filesystem::path& path) {
  TetGenParser parser(0, 1);
  MeshBlock all = parser.Parse(Stem(path));
  Mesh mesh;
  mesh.nodes = std::move(all.nodes);
  mesh.tets = std::move(all.tets);
  mesh.triangles = std::move(all.triangles);
  mesh.groups = std::move(all.groups);
  mesh.Validate(parser.source());
  return mesh;
}

MeshBlock ReadTetGenBlock(const std::filesystem::path& path, int rank, int size) {
  GIPSI_CHECK(size >= 1 && rank >= 0 && rank < size, "block {} of {}", rank, size);
  return TetGenParser(rank, size).Parse(Stem(path));
}

}  // namespace gipsi
