/// @file
/// One block of a Gmsh mesh (formats 1.0, 2.x and 4.1), streamed (see the header).

#include "gipsi/io/gmsh_block_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/io/chunked_file.h"
#include "gipsi/io/gmsh_elements.h"
#include "gipsi/io/mesh_builder.h"
#include "gipsi/io/text_reader.h"

namespace gipsi {
namespace {

using internal::ChunkedFile;
using internal::ElementInfo;
using internal::GetElementInfo;
using internal::Quote;
using internal::SplitTokens;
using Key = std::pair<int, int>;  // (dimension, physical tag)

/// Reads a Gmsh file in two passes: the first checks all of it and counts the nodes, tets
/// and triangles; the second keeps the block's items.
class BlockParser {
 public:
  BlockParser(const std::filesystem::path& path, int rank, int size)
      : f_(path), rank_(rank), size_(size) {}

  std::optional<MeshBlock> Read() {
    if (!Pass(false)) return std::nullopt;
    Prepare();
    (void)Pass(true);
    for (MeshGroup& group : block_.groups)
      if (group.dim == 0) {
        std::sort(group.items.begin(), group.items.end());
        group.items.erase(std::unique(group.items.begin(), group.items.end()), group.items.end());
      }
    return std::move(block_);
  }

 private:
  // One pass over the file; false if it is not read in blocks (first pass only).
  bool Pass(bool extract) {
    f_.Rewind();
    bool have_format = false, have_nodes = false, have_elements = false;
    std::string_view line;
    while (f_.NextContentLine(&line)) {
      if (line == "$MeshFormat") {
        if (!ReadFormat()) return false;
        have_format = true;
      } else if (line == "$NOD" || line == "$Nodes") {
        if (line == "$Nodes" && !have_format) f_.Fail("$Nodes before $MeshFormat");
        if (have_nodes) return false;  // more than one node section: read whole
        if (line == "$NOD") {
          major_ = 1;
          have_format = true;
          NodesV1V2(extract, "$ENDNOD");
        } else if (major_ == 4) {
          Nodes(extract);
        } else {
          NodesV1V2(extract, "$EndNodes");
        }
        have_nodes = true;
      } else if (line == "$ELM" || line == "$Elements") {
        if (line == "$Elements" && !have_format) f_.Fail("$Elements before $MeshFormat");
        if (!have_nodes)
          f_.Fail(fmt::format("{} before {}", line, line == "$ELM" ? "$NOD" : "$Nodes"));
        if (have_elements) return false;  // more than one element section: read whole
        have_elements = true;
        const bool done = line == "$ELM" ? ElementsV1V2(extract, "$ENDELM", true)
                          : major_ == 4  ? Elements(extract)
                                         : ElementsV1V2(extract, "$EndElements", false);
        if (!done) return false;
      } else if (line == "$PhysicalNames" && !extract) {
        PhysicalNames();
      } else if (line == "$Entities" && major_ == 4 && !extract) {
        Entities();
      } else if (line.front() == '$') {
        const std::string name(line.substr(1));
        const std::string end = "$End" + name;
        if (!f_.SkipPast(end)) f_.Fail(fmt::format("section ${} is not closed by {}", name, end));
      } else {
        f_.Fail(fmt::format(
            "expected a section header such as $MeshFormat, $Nodes or $Elements, got {}",
            Quote(line)));
      }
    }
    if (!have_nodes) f_.Fail("expected a $Nodes (or $NOD) section, got end of file");
    return true;
  }

  void ExpectEnd(std::string_view marker) {
    const std::string_view line = f_.RequireContentLine(marker);
    if (line != marker) f_.Fail(fmt::format("expected {}, got {}", marker, Quote(line)));
  }
  [[noreturn]] void Fail(std::string_view what) const {
    if (binary_) f_.FailAtOffset(fmt::format("in {}: {}", section_, what));
    f_.Fail(what);
  }
  std::int64_t ToInt(std::string_view token, std::string_view what) const {
    std::int64_t value = 0;
    if (!internal::TryParseInt(token, &value))
      f_.Fail(fmt::format("expected {}, got {}", what, Quote(token)));
    return value;
  }
  double ToFinite(std::string_view token, std::string_view what) const {
    double value = 0;
    if (!internal::TryParseDouble(token, &value) || !std::isfinite(value))
      f_.Fail(fmt::format("expected {} (a finite number), got {}", what, Quote(token)));
    return value;
  }
  std::int64_t Int(std::string_view what) {
    if (!binary_) return ToInt(f_.Token(what), what);
    return internal::LoadScalar<std::int32_t>(f_.Bytes(4, what).data(), swap_);
  }
  std::int64_t Size(std::string_view what) {
    if (!binary_) return ToInt(f_.Token(what), what);
    const char* p = f_.Bytes(static_cast<std::size_t>(size_bytes_), what).data();
    const std::uint64_t v = size_bytes_ == 8 ? internal::LoadScalar<std::uint64_t>(p, swap_)
                                             : internal::LoadScalar<std::uint32_t>(p, swap_);
    if (v > static_cast<std::uint64_t>(INT64_MAX)) Fail(fmt::format("{} {} is too large", what, v));
    return static_cast<std::int64_t>(v);
  }
  double Coord(std::string_view what) {
    if (!binary_) return ToFinite(f_.Token(what), what);
    const double v = internal::LoadScalar<double>(f_.Bytes(8, what).data(), swap_);
    if (!std::isfinite(v)) Fail(fmt::format("expected {} (a finite number), got {}", what, v));
    return v;
  }
  void SkipDouble(std::string_view what) {
    if (binary_)
      (void)f_.Bytes(8, what);
    else
      (void)ToFinite(f_.Token(what), what);
  }
  // Rejects a count that cannot fit in the rest of the file (bytes per item: ASCII, binary).
  std::int64_t CheckedCount(std::int64_t n, std::size_t ascii_bytes, std::size_t binary_bytes,
                            std::string_view what) const {
    if (n < 0) Fail(fmt::format("expected a non-negative number of {}, got {}", what, n));
    const std::size_t each = std::max<std::size_t>(binary_ ? binary_bytes : ascii_bytes, 1);
    if (static_cast<std::uint64_t>(n) > f_.remaining() / each)
      Fail(fmt::format("declares {} {}, but only {} bytes remain (truncated file?)", n, what,
                       f_.remaining()));
    return n;
  }

  // False for a version the whole reader reports (or refuses).
  bool ReadFormat() {
    const std::string_view line =
        f_.RequireContentLine("the format line 'version file-type data-size'");
    const auto t = SplitTokens(line);
    double version = 0;
    if (t.size() < 3 || !internal::TryParseDouble(t[0], &version))
      f_.Fail(fmt::format("expected 'version file-type data-size', got {}", Quote(line)));
    const std::int64_t file_type = ToInt(t[1], "file-type 0 (ASCII) or 1 (binary)");
    const std::int64_t data_size = ToInt(t[2], "the data size");
    if (version >= 2.0 && version < 3.0)
      major_ = 2;
    else if (version >= 4.1 && version < 5.0)
      major_ = 4;
    else
      return false;
    if (file_type != 0 && file_type != 1)
      f_.Fail(fmt::format("expected file-type 0 (ASCII) or 1 (binary), got {}", file_type));
    if ((major_ == 2 && data_size != 8) || (major_ == 4 && data_size != 8 && data_size != 4))
      f_.Fail(fmt::format("unsupported data size {}", data_size));
    size_bytes_ = static_cast<int>(data_size);
    if (file_type == 1) {
      const char* p = f_.Bytes(4, "the binary endianness check integer 1").data();
      if (internal::LoadScalar<std::int32_t>(p, false) == 1)
        swap_ = false;
      else if (internal::LoadScalar<std::int32_t>(p, true) == 1)
        swap_ = true;
      else
        f_.FailAtOffset("expected the binary endianness check integer 1");
    }
    ExpectEnd("$EndMeshFormat");
    binary_file_ = file_type == 1;
    return true;
  }

  void PhysicalNames() {
    const std::string_view count = f_.RequireContentLine("the number of physical names");
    const std::int64_t n = ToInt(count, "the number of physical names");
    if (n < 0 || static_cast<std::uint64_t>(n) > f_.remaining() / 6)
      f_.Fail(
          fmt::format("declares {} physical names, but only {} bytes remain", n, f_.remaining()));
    for (std::int64_t i = 0; i < n; ++i) {
      const std::string_view line =
          f_.RequireContentLine("a physical name line 'dim tag \"name\"'");
      const auto t = SplitTokens(line);
      const std::size_t q0 = line.find('"'), q1 = line.rfind('"');
      if (t.size() < 3 || q0 == std::string_view::npos || q1 == q0)
        f_.Fail(
            fmt::format("expected a physical name line 'dim tag \"name\"', got {}", Quote(line)));
      const int dim = static_cast<int>(ToInt(t[0], "a dimension"));
      const int tag = static_cast<int>(ToInt(t[1], "a physical tag"));
      if (dim < 0 || dim > 3) f_.Fail(fmt::format("expected a dimension 0..3, got {}", dim));
      names_[{dim, tag}] = std::string(line.substr(q0 + 1, q1 - q0 - 1));
    }
    ExpectEnd("$EndPhysicalNames");
  }

  void Entities() {
    Binary section(this, "$Entities");
    std::int64_t counts[4];
    for (auto& c : counts) c = Size("a number of entities");
    for (int dim = 0; dim < 4; ++dim) {
      const std::size_t bin = 4 + (dim == 0 ? 24 : 48) + 2 * static_cast<std::size_t>(size_bytes_);
      CheckedCount(counts[dim], 8, bin, "entities");
      for (std::int64_t i = 0; i < counts[dim]; ++i) {
        const int tag = static_cast<int>(Int("an entity tag"));
        for (int k = 0; k < (dim == 0 ? 3 : 6); ++k) SkipDouble("a coordinate");
        const std::int64_t num_physicals =
            CheckedCount(Size("a number of physical tags"), 2, 4, "physical tags");
        auto& list = entity_physicals_[{dim, tag}];
        for (std::int64_t k = 0; k < num_physicals; ++k) {
          const int p = static_cast<int>(Int("a physical tag"));
          if (p != 0) list.push_back(p < 0 ? -p : p);
        }
        if (dim > 0) {
          const std::int64_t num_bounding =
              CheckedCount(Size("a number of bounding entities"), 2, 4, "bounding entities");
          for (std::int64_t k = 0; k < num_bounding; ++k) (void)Int("a bounding entity tag");
        }
      }
    }
    section.End("$EndEntities");
  }

  // Marks a section whose values may be binary: errors then name byte offsets.
  struct Binary {
    Binary(BlockParser* p, const char* name) : p(p) {
      p->section_ = name;
      p->binary_ = p->binary_file_;
    }
    ~Binary() { p->binary_ = false; }
    void End(std::string_view marker) const {
      p->binary_ = false;
      p->ExpectEnd(marker);
    }
    Binary(const Binary&) = delete;
    Binary& operator=(const Binary&) = delete;
    BlockParser* p;
  };

  // The first pass learns how node tags map to indices: consecutive in file order (the usual
  // case, no table) or through a table sorted by tag.
  void NoteTag(std::int64_t tag, std::int64_t index) {
    if (index == 0) first_tag_ = tag;
    if (dense_ && tag == first_tag_ + index) return;
    if (dense_) {
      dense_ = false;
      table_.reserve(static_cast<std::size_t>(num_nodes_));
      for (std::int64_t j = 0; j < index; ++j) table_.emplace_back(first_tag_ + j, j);
    }
    table_.emplace_back(tag, index);
  }
  [[nodiscard]] std::int64_t IndexOf(std::int64_t tag) const {
    if (dense_) {
      const std::int64_t i = tag - first_tag_;
      return i >= 0 && i < num_nodes_ ? i : -1;
    }
    const auto it = std::lower_bound(table_.begin(), table_.end(), std::make_pair(tag, INT64_MIN));
    return it != table_.end() && it->first == tag ? it->second : -1;
  }

  void Nodes(bool extract) {
    Binary section(this, "$Nodes");
    const std::int64_t num_blocks = Size("the number of node blocks");
    const std::int64_t num_nodes = Size("the number of nodes");
    (void)Size("the minimum node tag");
    (void)Size("the maximum node tag");
    CheckedCount(num_blocks, 8, 12 + static_cast<std::size_t>(size_bytes_), "node blocks");
    CheckedCount(num_nodes, 8, 24 + static_cast<std::size_t>(size_bytes_), "nodes");
    if (!extract) {
      if (num_nodes > INT32_MAX) Fail(fmt::format("{} nodes: more than 2^31 - 1", num_nodes));
      num_nodes_ = num_nodes;
    }
    std::int64_t index = 0;
    for (std::int64_t block = 0; block < num_blocks; ++block) {
      const std::int64_t dim = Int("an entity dimension");
      (void)Int("an entity tag");
      const std::int64_t parametric = Int("the parametric flag");
      const std::int64_t n = Size("a number of nodes in the block");
      if (dim < 0 || dim > 3) Fail(fmt::format("expected an entity dimension 0..3, got {}", dim));
      CheckedCount(n, 8, 24 + static_cast<std::size_t>(size_bytes_), "nodes");
      if (index + n > num_nodes)
        Fail(fmt::format("node blocks hold more nodes than the declared {}", num_nodes));
      for (std::int64_t i = 0; i < n; ++i) {
        const std::int64_t tag = Size("a node tag");
        if (!extract) NoteTag(tag, index + i);
      }
      for (std::int64_t i = 0; i < n; ++i, ++index) {
        const double x = Coord("an x coordinate");
        const double y = Coord("a y coordinate");
        const double z = Coord("a z coordinate");
        for (std::int64_t k = 0; parametric != 0 && k < dim; ++k)
          SkipDouble("a parametric coordinate");
        if (extract && index >= r_.node_begin && index < r_.node_end)
          block_.nodes.col(static_cast<Index>(index - r_.node_begin)) = Vec3(x, y, z);
      }
    }
    if (index != num_nodes)
      Fail(fmt::format("expected {} nodes as declared, got {} in the blocks", num_nodes, index));
    section.End("$EndNodes");
    if (!extract) CheckTags("$Nodes");
  }

  // Sorts the tag table (if there is one) and refuses a tag defined twice in `section`.
  void CheckTags(std::string_view section) {
    if (dense_) return;
    std::sort(table_.begin(), table_.end());
    for (std::size_t i = 1; i < table_.size(); ++i)
      if (table_[i].first == table_[i - 1].first)
        f_.Fail(fmt::format("in {}: node tag {} is defined twice", section, table_[i].first));
  }

  // A count on its own line (ASCII in binary files too), as ReadGmsh reads it.
  std::int64_t CountLine(std::string_view what, std::size_t min_bytes_each,
                         std::string_view items) {
    const std::int64_t n = f_.ToInt(f_.RequireContentLine(what), what);
    f_.CheckCount(n, min_bytes_each, items);
    return n;
  }

  // Formats 1.0 ($NOD) and 2.x: a count, then `tag x y z` per node (binary 2.x: int32 tag and
  // three doubles).
  void NodesV1V2(bool extract, std::string_view end_marker) {
    const bool binary = binary_file_ && major_ == 2;
    const std::int64_t n = CountLine("the number of nodes", binary ? 28 : 8, "nodes");
    if (!extract) {
      if (n > INT32_MAX) f_.Fail(fmt::format("{} nodes: more than 2^31 - 1", n));
      num_nodes_ = n;
    }
    Binary section(this, "$Nodes");
    binary_ = binary;
    for (std::int64_t i = 0; i < n; ++i) {
      std::int64_t tag = 0;
      Vec3 x;
      if (binary) {
        const char* p = f_.Bytes(28, "node records").data();
        tag = internal::LoadScalar<std::int32_t>(p, swap_);
        for (int k = 0; k < 3; ++k) {
          x[k] = internal::LoadScalar<double>(p + 4 + 8 * k, swap_);
          if (!std::isfinite(x[k])) Fail(fmt::format("node {} has a non-finite coordinate", i));
        }
      } else {
        const std::string_view line = f_.RequireContentLine("a node line 'tag x y z'");
        const auto t = SplitTokens(line);
        if (line.front() == '$')
          f_.Fail(fmt::format("expected {} nodes as declared, got {} before {}", n, i, line));
        if (t.size() < 4)
          f_.Fail(fmt::format("expected a node line 'tag x y z', got {} values", t.size()));
        tag = ToInt(t[0], "a node tag");
        x = Vec3(ToFinite(t[1], "an x coordinate"), ToFinite(t[2], "a y coordinate"),
                 ToFinite(t[3], "a z coordinate"));
      }
      if (!extract) NoteTag(tag, i);
      if (extract && i >= r_.node_begin && i < r_.node_end)
        block_.nodes.col(static_cast<Index>(i - r_.node_begin)) = x;
    }
    section.End(end_marker);
    if (!extract) CheckTags(major_ == 1 ? "$NOD" : "$Nodes");
  }

  // Formats 1.0 and 2.x: `tag type ...` per element, the first tag its physical group (0: none).
  // False (first pass) for a second-order element.
  bool ElementsV1V2(bool extract, std::string_view end_marker, bool v1) {
    const bool binary = binary_file_ && major_ == 2 && !v1;
    const std::int64_t n = CountLine("the number of elements", binary ? 12 : 10, "elements");
    Binary section(this, "$Elements");
    binary_ = binary;
    tet_counter_ = triangle_counter_ = 0;
    auto add = [&](std::int64_t type, std::int64_t tag, std::int64_t physical) {
      const ElementInfo info = GetElementInfo(type);
      keys_.clear();
      if (physical != 0 && info.dim >= 0) keys_.emplace_back(info.dim, static_cast<int>(physical));
      if (!extract) {
        if (type == 11 || type == 9) return false;
        used_keys_.insert(keys_.begin(), keys_.end());
      }
      Element(type, tag, extract);
      return true;
    };
    if (binary) {
      for (std::int64_t done = 0; done < n;) {
        const std::int64_t type = Int("an element type");
        const std::int64_t follow = Int("a number of elements");
        const std::int64_t num_tags = Int("a number of tags");
        const ElementInfo info = GetElementInfo(type);
        if (info.nodes < 0) Fail(fmt::format("unsupported element type {}", type));
        if (follow <= 0 || follow > n - done || num_tags < 0 || num_tags > 1000)
          Fail(fmt::format("bad element block header ({} elements, {} tags)", follow, num_tags));
        const auto ints = static_cast<std::size_t>(1 + num_tags + info.nodes);
        CheckedCount(follow, 0, 4 * ints, "elements");
        for (std::int64_t e = 0; e < follow; ++e) {
          const char* p = f_.Bytes(4 * ints, "element records").data();
          auto at = [&](std::size_t k) {
            return internal::LoadScalar<std::int32_t>(p + 4 * k, swap_);
          };
          tags_.clear();
          for (int k = 0; k < info.nodes; ++k)
            tags_.push_back(at(1 + static_cast<std::size_t>(num_tags + k)));
          if (!add(type, at(0), num_tags > 0 ? at(1) : 0)) return false;
        }
        done += follow;
      }
    } else {
      for (std::int64_t i = 0; i < n; ++i) {
        const std::string_view line = f_.RequireContentLine("an element line");
        if (line.front() == '$')
          f_.Fail(fmt::format("expected {} elements as declared, got {} before {}", n, i, line));
        const auto t = SplitTokens(line);
        std::size_t first_node = v1 ? 5 : 3;
        if (t.size() < first_node)
          f_.Fail(fmt::format("expected an element line with at least {} values, got {}",
                              first_node, t.size()));
        const std::int64_t tag = ToInt(t[0], "an element number");
        const std::int64_t type = ToInt(t[1], "an element type");
        std::int64_t physical = 0;
        if (v1) {
          physical = ToInt(t[2], "a physical tag");
          const std::int64_t declared = ToInt(t[4], "a number of nodes");
          if (declared < 0 || static_cast<std::size_t>(declared) != t.size() - 5)
            f_.Fail(fmt::format("expected {} node indices as declared, got {}", declared,
                                t.size() - 5));
        } else {
          const std::int64_t num_tags = ToInt(t[2], "a number of tags");
          if (num_tags < 0 || static_cast<std::size_t>(num_tags) > t.size() - 3)
            f_.Fail(fmt::format("expected {} tags, got {} values", num_tags, t.size() - 3));
          if (num_tags > 0) physical = ToInt(t[3], "a physical tag");
          first_node += static_cast<std::size_t>(num_tags);
        }
        CheckNodeCount(GetElementInfo(type), t.size() - first_node);
        tags_.clear();
        for (std::size_t k = first_node; k < t.size(); ++k)
          tags_.push_back(ToInt(t[k], "a node tag"));
        if (!add(type, tag, physical)) return false;
      }
    }
    section.End(end_marker);
    return true;
  }

  void CheckNodeCount(const ElementInfo& info, std::size_t count) const {
    if (info.nodes >= 0 && count != static_cast<std::size_t>(info.nodes))
      f_.Fail(
          fmt::format("expected {} node indices for a {}, got {}", info.nodes, info.name, count));
  }

  // False (first pass) for a second-order element: such files are read whole.
  bool Elements(bool extract) {
    Binary section(this, "$Elements");
    const std::int64_t num_blocks = Size("the number of element blocks");
    (void)Size("the number of elements");
    (void)Size("the minimum element tag");
    (void)Size("the maximum element tag");
    CheckedCount(num_blocks, 8, 12 + static_cast<std::size_t>(size_bytes_), "element blocks");
    tet_counter_ = triangle_counter_ = 0;
    for (std::int64_t block = 0; block < num_blocks; ++block) {
      const int dim = static_cast<int>(Int("an entity dimension"));
      const int entity = static_cast<int>(Int("an entity tag"));
      const std::int64_t type = Int("an element type");
      const std::int64_t n = Size("a number of elements in the block");
      const ElementInfo info = GetElementInfo(type);
      if (!extract && (type == 11 || type == 9) && n > 0) return false;
      keys_.clear();
      if (auto it = entity_physicals_.find({dim, entity}); it != entity_physicals_.end())
        for (int p : it->second) keys_.emplace_back(dim, p);
      if (!extract && n > 0) used_keys_.insert(keys_.begin(), keys_.end());
      if (binary_) {
        if (info.nodes < 0) Fail(fmt::format("unsupported element type {}", type));
        const std::size_t per =
            static_cast<std::size_t>(size_bytes_) * (1 + static_cast<std::size_t>(info.nodes));
        CheckedCount(n, 0, per, "elements");
        for (std::int64_t e = 0; e < n; ++e) {
          const std::int64_t tag = Size("an element tag");
          tags_.clear();
          for (int k = 0; k < info.nodes; ++k) tags_.push_back(Size("a node tag"));
          Element(type, tag, extract);
        }
        continue;
      }
      CheckedCount(n, 4, 0, "elements");
      for (std::int64_t e = 0; e < n; ++e) {
        const std::string_view line = f_.RequireContentLine("an element line 'tag node...'");
        if (line.front() == '$')
          f_.Fail(fmt::format("expected {} elements in the block, got {} before {}", n, e, line));
        const auto t = SplitTokens(line);
        CheckNodeCount(info, t.size() - 1);
        tags_.clear();
        for (std::size_t k = 1; k < t.size(); ++k) tags_.push_back(ToInt(t[k], "a node tag"));
        Element(type, ToInt(t[0], "an element tag"), extract);
      }
    }
    section.End("$EndElements");
    return true;
  }

  void Element(std::int64_t type, std::int64_t tag, bool extract) {
    indices_.clear();
    for (const std::int64_t node : tags_) {
      const std::int64_t i = IndexOf(node);
      if (i < 0) Fail(fmt::format("element {} refers to undefined node {}", tag, node));
      indices_.push_back(static_cast<int>(i));
    }
    const bool tet = type == 4, triangle = type == 2;
    if (!extract) {
      if (tet || triangle)
        for (std::size_t a = 0; a < indices_.size(); ++a)
          for (std::size_t c = 0; c < a; ++c)
            if (indices_[a] == indices_[c])
              Fail(fmt::format("element {} repeats node {}", tag, tags_[a]));
      num_tets_ += tet ? 1 : 0;
      num_triangles_ += triangle ? 1 : 0;
      return;
    }
    std::int64_t item = -1;
    bool mine = false;
    if (tet) {
      item = tet_counter_++;
      mine = item >= r_.tet_begin && item < r_.tet_end;
      if (mine) {
        const auto column = static_cast<Index>(item - r_.tet_begin);
        for (int k = 0; k < 4; ++k) block_.tets(k, column) = indices_[static_cast<std::size_t>(k)];
        block_.tet_ids.push_back(tag);
      }
    } else if (triangle) {
      item = triangle_counter_++;
      mine = item >= r_.triangle_begin && item < r_.triangle_end;
      if (mine) {
        const auto column = static_cast<Index>(item - r_.triangle_begin);
        for (int k = 0; k < 3; ++k)
          block_.triangles(k, column) = indices_[static_cast<std::size_t>(k)];
      }
    }
    for (const Key& key : keys_) {
      std::vector<int>& items = block_.groups[group_of_.at(key)].items;
      if (key.first <= 1) {
        for (const int i : indices_)
          if (i >= r_.node_begin && i < r_.node_end) items.push_back(i);
      } else if (mine && ((key.first == 3 && tet) || (key.first == 2 && triangle))) {
        items.push_back(static_cast<int>(item));
      }
    }
  }

  // The block's ranges and storage, and the groups in ReadGmsh's order and names.
  void Prepare() {
    r_ = internal::StartBlock(block_, rank_, size_, num_nodes_, num_tets_, num_triangles_, f_);
    if (num_tets_ > 0) {
      block_.tet_ids.reserve(static_cast<std::size_t>(r_.tet_end - r_.tet_begin));
      block_.tet_id_kind = "Gmsh element tag";
    }
    std::set<Key> keys = used_keys_;
    for (const auto& [key, name] : names_) keys.insert(key);
    // Higher dimensions first, so that volumes keep their plain names on a clash (ReadGmsh).
    for (auto it = keys.rbegin(); it != keys.rend(); ++it) {
      MeshGroup group;
      const auto name = names_.find(*it);
      group.name = name != names_.end() ? name->second : fmt::format("physical_{}", it->second);
      group.dim = it->first <= 1 ? 0 : it->first;
      internal::AddUniqueGroup(block_.groups, std::move(group), fmt::format("_dim{}", it->first));
      group_of_[*it] = block_.groups.size() - 1;
    }
  }

  ChunkedFile f_;
  int rank_, size_;
  bool binary_file_ = false, binary_ = false, swap_ = false;
  int major_ = 1;  // Gmsh format: 1 ($NOD), 2 (2.x) or 4 (4.1)
  int size_bytes_ = 8;
  const char* section_ = "";
  // First pass.
  std::int64_t num_nodes_ = 0, num_tets_ = 0, num_triangles_ = 0;
  std::int64_t first_tag_ = 0;
  bool dense_ = true;
  std::vector<std::pair<std::int64_t, std::int64_t>> table_;  // (tag, index), when not dense
  std::map<Key, std::string> names_;
  std::map<Key, std::vector<int>> entity_physicals_;  // (entity dim, entity tag) -> tags
  std::set<Key> used_keys_;
  // Second pass.
  MeshBlock block_;
  std::map<Key, std::size_t> group_of_;
  internal::BlockRanges r_;  // the block's items
  std::int64_t tet_counter_ = 0, triangle_counter_ = 0;
  // Scratch.
  std::vector<Key> keys_;
  std::vector<std::int64_t> tags_;
  std::vector<int> indices_;
};

}  // namespace

std::optional<MeshBlock> ReadGmshBlock(const std::filesystem::path& path, int rank, int size) {
  GIPSI_CHECK(size >= 1 && rank >= 0 && rank < size);
  return BlockParser(path, rank, size).Read();
}

}  // namespace gipsi
