#include "gipsi/io/gmsh_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/edge_key.h"
#include "gipsi/io/gmsh_elements.h"
#include "gipsi/io/mesh_builder.h"
#include "gipsi/io/text_reader.h"

namespace gipsi {
namespace {

using internal::ElementInfo;
using internal::GetElementInfo;
using internal::Quote;
using internal::SplitTokens;
using internal::TextReader;

using Key = std::pair<int, int>;  // (dimension, physical tag)

class GmshParser {
 public:
  explicit GmshParser(TextReader& r) : r_(r) {}

  /// The element tag of every tet read, in order.
  [[nodiscard]] const std::vector<std::int64_t>& tet_tags() const { return tet_tags_; }

  Mesh Parse() {
    std::string_view line;
    while (r_.NextContentLine(&line)) {
      if (line == "$MeshFormat") {
        ReadMeshFormat();
      } else if (line == "$NOD") {
        ReadNodesAscii("$ENDNOD");
      } else if (line == "$ELM") {
        ReadElementsV1V2Ascii("$ENDELM", /*v1=*/true);
      } else if (line == "$PhysicalNames") {
        ReadPhysicalNames();
      } else if (line == "$Entities" && major_ == 4) {
        Section s(this, "$Entities");
        ReadEntities41();
      } else if (line == "$Nodes" || line == "$Elements") {
        if (!have_format_) r_.Fail(fmt::format("{} before $MeshFormat", line));
        bool nodes = line == "$Nodes";
        Section s(this, nodes ? "$Nodes" : "$Elements");
        if (major_ == 4) {
          nodes ? ReadNodes41() : ReadElements41();
        } else if (binary_) {
          nodes ? ReadNodesV2Binary() : ReadElementsV2Binary();
        } else {
          nodes ? ReadNodesAscii("$EndNodes") : ReadElementsV1V2Ascii("$EndElements", false);
        }
        (nodes ? have_nodes_ : have_elements_) = true;
      } else if (line.front() == '$') {
        SkipSection(line.substr(1));
      } else {
        r_.Fail(
            fmt::format("expected a section header such as $MeshFormat, $Nodes or $Elements, "
                        "got {}",
                        Quote(line)));
      }
      if (line == "$NOD") have_nodes_ = have_format_ = true;
    }
    if (!have_nodes_) r_.Fail("expected a $Nodes (or $NOD) section, got end of file");
    BuildGroups();
    Mesh mesh = b_.Build(r_.source());
    mesh.SeparateEdgeNodes(edge_middle_);
    mesh.Validate(r_.source());
    return mesh;
  }

 private:
  /// Marks the binary section being read so that errors report byte offsets.
  struct Section {
    Section(GmshParser* p, const char* name) : p(p) {
      p->section_ = name;
      p->in_binary_ = p->binary_;
    }
    ~Section() { p->in_binary_ = false; }
    Section(const Section&) = delete;
    Section& operator=(const Section&) = delete;
    GmshParser* p;
  };

  [[noreturn]] void Fail(std::string_view what) const {
    if (in_binary_) r_.FailAtOffset(fmt::format("in {}: {}", section_, what));
    r_.Fail(what);
  }

  void ExpectEnd(std::string_view marker) {
    in_binary_ = false;
    std::string_view line = r_.RequireContentLine(marker);
    if (line != marker) r_.Fail(fmt::format("expected {}, got {}", marker, Quote(line)));
  }

  void SkipSection(std::string_view name) {
    std::string end = fmt::format("$End{}", name);
    std::size_t at = r_.data().find(end, r_.offset());
    if (at == std::string_view::npos)
      r_.Fail(fmt::format("section ${} is not closed by {}", name, end));
    r_.Seek(at + end.size());
  }

  /// A count written on its own line (ASCII even in binary files).
  std::int64_t ReadCountLine(std::string_view what, std::size_t min_bytes_each,
                             std::string_view items) {
    std::string_view line = r_.RequireContentLine(what);
    std::int64_t n = r_.ToInt(line, what);
    r_.CheckCount(n, min_bytes_each, items);
    return n;
  }

  // Values of format 4.1 sections: ASCII tokens, or binary int / size_t / double.
  std::int64_t Int(std::string_view what) {
    if (!binary_) return r_.ReadInt(what);
    return internal::LoadScalar<std::int32_t>(r_.ReadBytes(4, what).data(), swap_);
  }
  std::int64_t Size(std::string_view what) {
    if (!binary_) return r_.ReadInt(what);
    const char* p = r_.ReadBytes(static_cast<std::size_t>(size_bytes_), what).data();
    std::uint64_t v = size_bytes_ == 8 ? internal::LoadScalar<std::uint64_t>(p, swap_)
                                       : internal::LoadScalar<std::uint32_t>(p, swap_);
    if (v > static_cast<std::uint64_t>(INT64_MAX)) Fail(fmt::format("{} {} is too large", what, v));
    return static_cast<std::int64_t>(v);
  }
  double Coord(std::string_view what) {
    if (!binary_) return r_.ReadFinite(what);
    double v = internal::LoadScalar<double>(r_.ReadBytes(8, what).data(), swap_);
    if (!std::isfinite(v)) Fail(fmt::format("expected {} (a finite number), got {}", what, v));
    return v;
  }
  void SkipDouble(std::string_view what) {
    if (binary_) {
      r_.ReadBytes(8, what);
      return;
    }
    double ignored = 0;
    std::string_view token = r_.RequireToken(what);
    if (!internal::TryParseDouble(token, &ignored))
      r_.Fail(fmt::format("expected {}, got {}", what, Quote(token)));
  }
  /// Rejects a count that cannot fit in the rest of the file (bytes per item: ASCII, binary).
  std::int64_t CheckedCount(std::int64_t n, std::size_t ascii_bytes, std::size_t binary_bytes,
                            std::string_view what) {
    if (n < 0) Fail(fmt::format("expected a non-negative number of {}, got {}", what, n));
    std::size_t each = std::max<std::size_t>(binary_ ? binary_bytes : ascii_bytes, 1);
    if (static_cast<std::uint64_t>(n) > r_.remaining() / each) {
      Fail(fmt::format("declares {} {}, but only {} bytes remain (truncated file?)", n, what,
                       r_.remaining()));
    }
    return n;
  }

  void ReadMeshFormat() {
    std::string_view line = r_.RequireContentLine("the format line 'version file-type data-size'");
    auto t = SplitTokens(line);
    double version = 0;
    if (t.size() < 3 || !internal::TryParseDouble(t[0], &version))
      r_.Fail(fmt::format("expected 'version file-type data-size', got {}", Quote(line)));
    std::int64_t file_type = r_.ToInt(t[1], "file-type 0 (ASCII) or 1 (binary)");
    std::int64_t data_size = r_.ToInt(t[2], "the data size");
    if (version >= 2.0 && version < 3.0) {
      major_ = 2;
    } else if (version >= 4.1 && version < 5.0) {
      major_ = 4;
    } else {
      r_.Fail(
          fmt::format("unsupported Gmsh format version {} (supported: 1.0, 2.2, 4.1; "
                      "re-save the mesh as 4.1 or 2.2)",
                      t[0]));
    }
    if (file_type != 0 && file_type != 1)
      r_.Fail(fmt::format("expected file-type 0 (ASCII) or 1 (binary), got {}", file_type));
    binary_ = file_type == 1;
    if ((major_ == 2 && data_size != 8) || (major_ == 4 && data_size != 8 && data_size != 4))
      r_.Fail(fmt::format("unsupported data size {}", data_size));
    size_bytes_ = static_cast<int>(data_size);
    if (binary_) {
      const char* p = r_.ReadBytes(4, "the binary endianness check integer 1").data();
      if (internal::LoadScalar<std::int32_t>(p, false) == 1) {
        swap_ = false;
      } else if (internal::LoadScalar<std::int32_t>(p, true) == 1) {
        swap_ = true;
      } else {
        r_.FailAtOffset("expected the binary endianness check integer 1", r_.offset() - 4);
      }
    }
    have_format_ = true;
    ExpectEnd("$EndMeshFormat");
  }

  void ReadPhysicalNames() {
    std::int64_t n = ReadCountLine("the number of physical names", 6, "physical names");
    for (std::int64_t i = 0; i < n; ++i) {
      std::string_view line = r_.RequireContentLine("a physical name line 'dim tag \"name\"'");
      auto t = SplitTokens(line);
      std::size_t q0 = line.find('"');
      std::size_t q1 = line.rfind('"');
      if (t.size() < 3 || q0 == std::string_view::npos || q1 == q0)
        r_.Fail(
            fmt::format("expected a physical name line 'dim tag \"name\"', got {}", Quote(line)));
      int dim = static_cast<int>(r_.ToInt(t[0], "a dimension"));
      int tag = static_cast<int>(r_.ToInt(t[1], "a physical tag"));
      if (dim < 0 || dim > 3) r_.Fail(fmt::format("expected a dimension 0..3, got {}", dim));
      names_[{dim, tag}] = std::string(line.substr(q0 + 1, q1 - q0 - 1));
    }
    ExpectEnd("$EndPhysicalNames");
  }

  void AddNode(std::int64_t tag, double x, double y, double z) {
    if (!nodes_.Insert(tag)) Fail(fmt::format("node tag {} is defined twice", tag));
    b_.AddNode(x, y, z);
  }

  void ReadNodesAscii(std::string_view end_marker) {
    std::int64_t n = ReadCountLine("the number of nodes", 8, "nodes");
    nodes_.Reserve(static_cast<std::size_t>(n));
    b_.coords.reserve(static_cast<std::size_t>(3 * n));
    for (std::int64_t i = 0; i < n; ++i) {
      std::string_view line = r_.RequireContentLine("a node line 'tag x y z'");
      auto t = SplitTokens(line);
      if (line.front() == '$')
        r_.Fail(fmt::format("expected {} nodes as declared, got {} before {}", n, i, line));
      if (t.size() < 4)
        r_.Fail(fmt::format("expected a node line 'tag x y z', got {} values", t.size()));
      AddNode(r_.ToInt(t[0], "a node tag"), r_.ToFinite(t[1], "an x coordinate"),
              r_.ToFinite(t[2], "a y coordinate"), r_.ToFinite(t[3], "a z coordinate"));
    }
    ExpectEnd(end_marker);
  }

  void ReadNodesV2Binary() {
    std::int64_t n = ReadCountLine("the number of nodes", 28, "nodes");
    in_binary_ = true;
    std::string_view bytes = r_.ReadBytes(static_cast<std::size_t>(n) * 28, "node records");
    for (std::int64_t i = 0; i < n; ++i) {
      const char* p = bytes.data() + 28 * i;
      double xyz[3];
      for (int k = 0; k < 3; ++k) {
        xyz[k] = internal::LoadScalar<double>(p + 4 + 8 * k, swap_);
        if (!std::isfinite(xyz[k])) Fail(fmt::format("node {} has a non-finite coordinate", i));
      }
      AddNode(internal::LoadScalar<std::int32_t>(p, swap_), xyz[0], xyz[1], xyz[2]);
    }
    ExpectEnd("$EndNodes");
  }

  void ReadElementsV1V2Ascii(std::string_view end_marker, bool v1) {
    std::int64_t n = ReadCountLine("the number of elements", 10, "elements");
    for (std::int64_t i = 0; i < n; ++i) {
      std::string_view line = r_.RequireContentLine("an element line");
      if (line.front() == '$')
        r_.Fail(fmt::format("expected {} elements as declared, got {} before {}", n, i, line));
      auto t = SplitTokens(line);
      std::size_t first_node = v1 ? 5 : 3;
      if (t.size() < first_node)
        r_.Fail(fmt::format("expected an element line with at least {} values, got {}", first_node,
                            t.size()));
      std::int64_t tag = r_.ToInt(t[0], "an element number");
      std::int64_t type = r_.ToInt(t[1], "an element type");
      std::int64_t physical = 0;
      if (v1) {
        physical = r_.ToInt(t[2], "a physical tag");
        std::int64_t declared = r_.ToInt(t[4], "a number of nodes");
        if (declared < 0 || static_cast<std::size_t>(declared) != t.size() - 5)
          r_.Fail(
              fmt::format("expected {} node indices as declared, got {}", declared, t.size() - 5));
      } else {
        std::int64_t num_tags = r_.ToInt(t[2], "a number of tags");
        if (num_tags < 0 || static_cast<std::size_t>(num_tags) > t.size() - 3)
          r_.Fail(fmt::format("expected {} tags, got {} values", num_tags, t.size() - 3));
        if (num_tags > 0) physical = r_.ToInt(t[3], "a physical tag");
        first_node += static_cast<std::size_t>(num_tags);
      }
      ElementInfo info = GetElementInfo(type);
      std::size_t count = t.size() - first_node;
      CheckNodeCount(info, count);
      tags_.clear();
      for (std::size_t k = first_node; k < t.size(); ++k)
        tags_.push_back(r_.ToInt(t[k], "a node tag"));
      keys_.clear();
      if (physical != 0 && info.dim >= 0) keys_.emplace_back(info.dim, int(physical));
      AddElement(type, tag);
    }
    ExpectEnd(end_marker);
  }

  void ReadElementsV2Binary() {
    std::int64_t n = ReadCountLine("the number of elements", 12, "elements");
    in_binary_ = true;
    std::int64_t done = 0;
    while (done < n) {
      std::int64_t type = Int("an element type");
      std::int64_t follow = Int("a number of elements");
      std::int64_t num_tags = Int("a number of tags");
      ElementInfo info = GetElementInfo(type);
      if (info.nodes < 0) Fail(fmt::format("unsupported element type {}", type));
      if (follow <= 0 || follow > n - done || num_tags < 0 || num_tags > 1000)
        Fail(fmt::format("bad element block header ({} elements, {} tags)", follow, num_tags));
      std::size_t ints = 1 + static_cast<std::size_t>(num_tags + info.nodes);
      CheckedCount(follow, 0, 4 * ints, "elements");
      std::string_view bytes =
          r_.ReadBytes(static_cast<std::size_t>(follow) * 4 * ints, "element records");
      for (std::int64_t e = 0; e < follow; ++e) {
        auto at = [&](std::size_t k) {
          return internal::LoadScalar<std::int32_t>(bytes.data() + 4 * (e * ints + k), swap_);
        };
        tags_.clear();
        for (int k = 0; k < info.nodes; ++k)
          tags_.push_back(at(1 + static_cast<std::size_t>(num_tags + k)));
        keys_.clear();
        if (num_tags > 0 && at(1) != 0) keys_.emplace_back(info.dim, at(1));
        AddElement(type, at(0));
      }
      done += follow;
    }
    ExpectEnd("$EndElements");
  }

  void ReadEntities41() {
    std::int64_t counts[4];
    for (auto& c : counts) c = Size("a number of entities");
    for (int dim = 0; dim < 4; ++dim) {
      std::size_t bin = 4 + (dim == 0 ? 24 : 48) + 2 * static_cast<std::size_t>(size_bytes_);
      CheckedCount(counts[dim], 8, bin, "entities");
      for (std::int64_t i = 0; i < counts[dim]; ++i) {
        int tag = static_cast<int>(Int("an entity tag"));
        for (int k = 0; k < (dim == 0 ? 3 : 6); ++k) SkipDouble("a coordinate");
        std::int64_t num_physicals =
            CheckedCount(Size("a number of physical tags"), 2, 4, "physical tags");
        auto& list = entity_physicals_[{dim, tag}];
        for (std::int64_t k = 0; k < num_physicals; ++k) {
          int p = static_cast<int>(Int("a physical tag"));
          if (p != 0) list.push_back(p < 0 ? -p : p);
        }
        if (dim > 0) {
          std::int64_t num_bounding =
              CheckedCount(Size("a number of bounding entities"), 2, 4, "bounding entities");
          for (std::int64_t k = 0; k < num_bounding; ++k) Int("a bounding entity tag");
        }
      }
    }
    ExpectEnd("$EndEntities");
  }

  void ReadNodes41() {
    std::int64_t num_blocks = Size("the number of node blocks");
    std::int64_t num_nodes = Size("the number of nodes");
    Size("the minimum node tag");
    Size("the maximum node tag");
    CheckedCount(num_blocks, 8, 12 + static_cast<std::size_t>(size_bytes_), "node blocks");
    CheckedCount(num_nodes, 8, 24 + static_cast<std::size_t>(size_bytes_), "nodes");
    nodes_.Reserve(static_cast<std::size_t>(num_nodes));
    b_.coords.reserve(static_cast<std::size_t>(3 * num_nodes));
    std::vector<std::int64_t> tags;
    std::int64_t total = 0;
    for (std::int64_t block = 0; block < num_blocks; ++block) {
      std::int64_t dim = Int("an entity dimension");
      Int("an entity tag");
      std::int64_t parametric = Int("the parametric flag");
      std::int64_t n = Size("a number of nodes in the block");
      if (dim < 0 || dim > 3) Fail(fmt::format("expected an entity dimension 0..3, got {}", dim));
      CheckedCount(n, 8, 24 + static_cast<std::size_t>(size_bytes_), "nodes");
      total += n;
      if (total > num_nodes)
        Fail(fmt::format("node blocks hold more nodes than the declared {}", num_nodes));
      tags.resize(static_cast<std::size_t>(n));
      for (auto& tag : tags) tag = Size("a node tag");
      for (std::int64_t tag : tags) {
        double x = Coord("an x coordinate");
        double y = Coord("a y coordinate");
        double z = Coord("a z coordinate");
        for (std::int64_t k = 0; parametric != 0 && k < dim; ++k)
          SkipDouble("a parametric coordinate");
        AddNode(tag, x, y, z);
      }
    }
    if (total != num_nodes)
      Fail(fmt::format("expected {} nodes as declared, got {} in the blocks", num_nodes, total));
    ExpectEnd("$EndNodes");
  }

  void ReadElements41() {
    std::int64_t num_blocks = Size("the number of element blocks");
    Size("the number of elements");
    Size("the minimum element tag");
    Size("the maximum element tag");
    CheckedCount(num_blocks, 8, 12 + static_cast<std::size_t>(size_bytes_), "element blocks");
    for (std::int64_t block = 0; block < num_blocks; ++block) {
      int dim = static_cast<int>(Int("an entity dimension"));
      int entity = static_cast<int>(Int("an entity tag"));
      std::int64_t type = Int("an element type");
      std::int64_t n = Size("a number of elements in the block");
      ElementInfo info = GetElementInfo(type);
      keys_.clear();
      if (auto it = entity_physicals_.find({dim, entity}); it != entity_physicals_.end())
        for (int p : it->second) keys_.emplace_back(dim, p);
      if (binary_) {
        if (info.nodes < 0) Fail(fmt::format("unsupported element type {}", type));
        std::size_t per = static_cast<std::size_t>(size_bytes_) * (1 + std::size_t(info.nodes));
        CheckedCount(n, 0, per, "elements");
        for (std::int64_t e = 0; e < n; ++e) {
          std::int64_t tag = Size("an element tag");
          tags_.clear();
          for (int k = 0; k < info.nodes; ++k) tags_.push_back(Size("a node tag"));
          AddElement(type, tag);
        }
        continue;
      }
      CheckedCount(n, 4, 0, "elements");
      for (std::int64_t e = 0; e < n; ++e) {
        std::string_view line = r_.RequireContentLine("an element line 'tag node...'");
        if (line.front() == '$')
          r_.Fail(fmt::format("expected {} elements in the block, got {} before {}", n, e, line));
        auto t = SplitTokens(line);
        CheckNodeCount(info, t.size() - 1);
        tags_.clear();
        for (std::size_t k = 1; k < t.size(); ++k) tags_.push_back(r_.ToInt(t[k], "a node tag"));
        AddElement(type, r_.ToInt(t[0], "an element tag"));
      }
    }
    ExpectEnd("$EndElements");
  }

  void CheckNodeCount(const ElementInfo& info, std::size_t count) const {
    if (info.nodes >= 0 && count != static_cast<std::size_t>(info.nodes))
      Fail(fmt::format("expected {} node indices for a {}, got {}", info.nodes, info.name, count));
  }

  /// Adds the element whose node tags are in `tags_` and physical groups in `keys_`.
  void AddElement(std::int64_t type, std::int64_t tag) {
    idx_.clear();
    for (std::int64_t node : tags_) {
      int i = nodes_.Find(node);
      if (i < 0) Fail(fmt::format("element {} refers to undefined node {}", tag, node));
      idx_.push_back(i);
    }
    bool tet = type == 4 || type == 11;
    bool tri = type == 2 || type == 9;
    if (tet || tri) {
      const std::size_t count = idx_.size();
      for (std::size_t a = 0; a < count; ++a)
        for (std::size_t c = 0; c < a; ++c)
          if (idx_[a] == idx_[c]) Fail(fmt::format("element {} repeats node {}", tag, tags_[a]));
    }
    if (type == 11 || type == 9) AddEdgeNodes(type == 11, tag);
    int item = -1;
    if (tet) {
      item = b_.AddTet(idx_[0], idx_[1], idx_[2], idx_[3]);
      tet_tags_.push_back(tag);
    }
    if (tri) item = b_.AddTriangle(idx_[0], idx_[1], idx_[2]);
    for (const Key& key : keys_) {
      auto& items = members_[key];
      if (key.first <= 1) {
        items.insert(items.end(), idx_.begin(), idx_.end());
      } else if ((key.first == 3 && tet) || (key.first == 2 && tri)) {
        items.push_back(item);
      }
    }
  }

  /// Records the middle nodes of a 10-node tet's or 6-node triangle's edges (node indices in
  /// `idx_`, Gmsh's local order: after the corners, the edges (0,1), (1,2), (2,0), then for
  /// tets (3,0), (3,2), (3,1)). Fails if another element put a different node in the middle
  /// of the same edge (a non-conforming mesh).
  void AddEdgeNodes(bool tet, std::int64_t tag) {
    const auto& kEdges = kGmshSecondOrderEdges;
    const int corners = tet ? 4 : 3;
    for (int k = 0; k < (tet ? 6 : 3); ++k) {
      const int a = idx_[std::size_t(kEdges[k][0])], b = idx_[std::size_t(kEdges[k][1])];
      const int middle = idx_[std::size_t(corners + k)];
      const auto [it, inserted] = edge_middle_.emplace(EdgeKey(a, b), middle);
      if (inserted || it->second == middle) continue;
      const std::size_t p = 3 * std::size_t(middle), q = 3 * std::size_t(it->second);
      if (std::equal(b_.coords.begin() + std::ptrdiff_t(p),
                     b_.coords.begin() + std::ptrdiff_t(p + 3),
                     b_.coords.begin() + std::ptrdiff_t(q)))
        continue;
      Fail(
          fmt::format("element {} puts node {} in the middle of the edge between nodes {} and "
                      "{}, where another element has a node elsewhere: the second-order mesh "
                      "is not conforming",
                      tag, tags_[std::size_t(corners + k)], tags_[std::size_t(kEdges[k][0])],
                      tags_[std::size_t(kEdges[k][1])]));
    }
  }

  void BuildGroups() {
    std::set<Key> keys;
    for (const auto& [key, name] : names_) keys.insert(key);
    for (const auto& [key, items] : members_) keys.insert(key);
    // Higher dimensions first, so that volumes keep their plain names on a clash.
    for (auto it = keys.rbegin(); it != keys.rend(); ++it) {
      const Key& key = *it;
      MeshGroup group;
      auto name = names_.find(key);
      group.name = name != names_.end() ? name->second : fmt::format("physical_{}", key.second);
      group.dim = key.first <= 1 ? 0 : key.first;
      if (auto m = members_.find(key); m != members_.end()) group.items = std::move(m->second);
      if (group.dim == 0) {
        std::sort(group.items.begin(), group.items.end());
        group.items.erase(std::unique(group.items.begin(), group.items.end()), group.items.end());
      }
      internal::AddUniqueGroup(b_.groups, std::move(group), fmt::format("_dim{}", key.first));
    }
  }

  TextReader& r_;
  int major_ = 1;
  bool have_format_ = false;
  bool have_nodes_ = false;
  bool have_elements_ = false;
  bool binary_ = false;
  bool swap_ = false;
  bool in_binary_ = false;
  const char* section_ = "";
  int size_bytes_ = 8;
  internal::MeshBuilder b_;
  internal::TagMap nodes_;
  std::map<Key, std::string> names_;
  std::map<Key, std::vector<int>> members_;
  std::map<Key, std::vector<int>> entity_physicals_;  // (entity dim, entity tag) -> tags
  std::vector<std::int64_t> tags_;                    // scratch: node tags of one element
  std::vector<int> idx_;                              // scratch: node indices of one element
  std::vector<std::int64_t> tet_tags_;                // element tag of every tet, in order
  std::vector<Key> keys_;                             // scratch: physical groups of one element
  std::map<std::uint64_t, int> edge_middle_;  // second-order edge (min·2³² + max) -> middle node
};

}  // namespace

Mesh ReadGmsh(const std::filesystem::path& path) { return ReadGmsh(path, nullptr); }

Mesh ReadGmsh(const std::filesystem::path& path, std::vector<std::int64_t>* tet_tags) {
  TextReader reader = TextReader::FromFile(path);
  GmshParser parser(reader);
  Mesh mesh = parser.Parse();
  if (tet_tags) *tet_tags = parser.tet_tags();
  return mesh;
}

}  // namespace gipsi
