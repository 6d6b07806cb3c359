#include "gipsi/geometry/mesh.h"

#include <algorithm>
#include <set>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/edge_key.h"

namespace gipsi {
namespace {

template <class Conn>
void CheckConnectivity(const Conn& conn, Index num_nodes, std::string_view kind,
                       std::string_view source) {
  for (Index e = 0; e < conn.cols(); ++e) {
    for (Index a = 0; a < conn.rows(); ++a) {
      int n = conn(a, e);
      if (n < 0 || n >= num_nodes) {
        ThrowInputError(source, fmt::format("{} {}", kind, e),
                        fmt::format("node index {} out of range [0, {})", n, num_nodes));
      }
      for (Index b = 0; b < a; ++b) {
        if (conn(b, e) == n)
          ThrowInputError(source, fmt::format("{} {}", kind, e), fmt::format("repeats node {}", n));
      }
    }
  }
}

}  // namespace

const MeshGroup* Mesh::FindGroup(std::string_view name) const {
  for (const auto& g : groups)
    if (g.name == name) return &g;
  return nullptr;
}

std::string Mesh::TetName(Index e) const {
  return fmt::format("tet {} ({})", TetId(e), TetIdKind());
}

std::string Mesh::TetIdList(const std::vector<int>& tets) const {
  std::string out;
  for (std::size_t i = 0; i < tets.size() && i < 10; ++i)
    out += fmt::format("{}{}", i ? ", " : "", TetId(tets[i]));
  if (tets.size() > 10) out += fmt::format(", ... ({} more)", tets.size() - 10);
  return fmt::format("{} ({})", out,
                     tet_ids.empty() ? "0-based indices in file order" : tet_id_kind + "s");
}

void Mesh::Validate(std::string_view source) const {
  if (!nodes.allFinite()) {
    for (Index i = 0; i < nodes.cols(); ++i)
      if (!nodes.col(i).allFinite())
        ThrowInputError(source, fmt::format("node {}", i), "coordinates are not finite");
  }
  CheckConnectivity(tets, num_nodes(), "tetrahedron", source);
  CheckConnectivity(triangles, num_nodes(), "triangle", source);
  if (edge_nodes.cols() != edge_node_ends.cols())
    ThrowInputError(source, "",
                    fmt::format("{} second-order edge nodes for {} edges", edge_nodes.cols(),
                                edge_node_ends.cols()));
  for (Index k = 0; k < edge_node_ends.cols(); ++k) {
    const int a = edge_node_ends(0, k), b = edge_node_ends(1, k);
    if (a < 0 || b >= num_nodes() || a >= b)
      ThrowInputError(source, fmt::format("second-order edge {}", k),
                      fmt::format("ends {} and {} are not two nodes in [0, {}), smaller first", a,
                                  b, num_nodes()));
    if (!edge_nodes.col(k).allFinite())
      ThrowInputError(source, fmt::format("second-order edge {}", k),
                      "the middle node's coordinates are not finite");
  }
  if (!tet_ids.empty() && static_cast<Index>(tet_ids.size()) != num_tets())
    ThrowInputError(source, "", fmt::format("{} tet ids for {} tets", tet_ids.size(), num_tets()));
  std::set<std::string> names;
  for (const auto& g : groups) {
    if (!names.insert(g.name).second)
      ThrowInputError(source, fmt::format("group '{}'", g.name), "duplicate group name");
    Index limit = g.dim == 0 ? num_nodes() : g.dim == 2 ? num_triangles() : num_tets();
    if (g.dim != 0 && g.dim != 2 && g.dim != 3)
      ThrowInputError(source, fmt::format("group '{}'", g.name),
                      fmt::format("dimension {} is not 0, 2 or 3", g.dim));
    for (int i : g.items)
      if (i < 0 || i >= limit)
        ThrowInputError(source, fmt::format("group '{}'", g.name),
                        fmt::format("item {} out of range [0, {})", i, limit));
  }
}

std::vector<int> Mesh::RemoveUnusedNodes() {
  std::vector<std::uint8_t> used(static_cast<std::size_t>(num_nodes()), 0);
  if (num_tets() == 0 && num_triangles() == 0) std::fill(used.begin(), used.end(), 1);
  auto mark = [&](auto& conn) {
    for (Index e = 0; e < conn.cols(); ++e)
      for (Index a = 0; a < conn.rows(); ++a) used[static_cast<std::size_t>(conn(a, e))] = 1;
  };
  mark(tets);
  mark(triangles);
  return KeepNodes(used);
}

std::vector<int> Mesh::KeepNodes(const std::vector<std::uint8_t>& keep) {
  GIPSI_CHECK(static_cast<Index>(keep.size()) == num_nodes(), "KeepNodes: {} flags for {} nodes",
              keep.size(), num_nodes());
  std::vector<int> old_of_new;
  std::vector<int> new_of_old(keep.size(), -1);
  for (std::size_t i = 0; i < keep.size(); ++i) {
    if (keep[i]) {
      new_of_old[i] = static_cast<int>(old_of_new.size());
      old_of_new.push_back(static_cast<int>(i));
    }
  }
  Points kept(3, static_cast<Index>(old_of_new.size()));
  for (std::size_t j = 0; j < old_of_new.size(); ++j)
    kept.col(static_cast<Index>(j)) = nodes.col(old_of_new[j]);
  nodes = std::move(kept);
  auto renumber = [&](auto& conn) {
    for (Index e = 0; e < conn.cols(); ++e)
      for (Index a = 0; a < conn.rows(); ++a) {
        const int n = new_of_old[static_cast<std::size_t>(conn(a, e))];
        GIPSI_CHECK(n >= 0, "KeepNodes: an element refers to dropped node {}", conn(a, e));
        conn(a, e) = n;
      }
  };
  renumber(tets);
  renumber(triangles);
  for (auto& g : groups) {
    if (g.dim != 0) continue;
    std::vector<int> items;
    for (int i : g.items)
      if (new_of_old[static_cast<std::size_t>(i)] >= 0)
        items.push_back(new_of_old[static_cast<std::size_t>(i)]);
    g.items = std::move(items);
  }
  Index kept_edges = 0;
  for (Index k = 0; k < edge_node_ends.cols(); ++k) {
    const int a = new_of_old[static_cast<std::size_t>(edge_node_ends(0, k))];
    const int b = new_of_old[static_cast<std::size_t>(edge_node_ends(1, k))];
    if (a < 0 || b < 0) continue;
    edge_node_ends(0, kept_edges) = std::min(a, b);
    edge_node_ends(1, kept_edges) = std::max(a, b);
    edge_nodes.col(kept_edges) = edge_nodes.col(k);
    ++kept_edges;
  }
  edge_node_ends.conservativeResize(2, kept_edges);
  edge_nodes.conservativeResize(3, kept_edges);
  return old_of_new;
}

void Mesh::SeparateEdgeNodes(const std::map<std::uint64_t, int>& middle_of_edge) {
  if (middle_of_edge.empty()) return;
  std::vector<std::uint8_t> keep(static_cast<std::size_t>(num_nodes()), 1);
  for (const auto& [key, middle] : middle_of_edge) keep[static_cast<std::size_t>(middle)] = 0;
  for (Index e = 0; e < num_tets(); ++e)
    for (int a = 0; a < 4; ++a) keep[static_cast<std::size_t>(tets(a, e))] = 1;
  for (Index t = 0; t < num_triangles(); ++t)
    for (int a = 0; a < 3; ++a) keep[static_cast<std::size_t>(triangles(a, t))] = 1;
  const auto count = static_cast<Index>(middle_of_edge.size());
  edge_node_ends.resize(2, count);
  edge_nodes.resize(3, count);
  Index k = 0;
  for (const auto& [key, middle] : middle_of_edge) {
    edge_node_ends(0, k) = EdgeKeyLow(key);
    edge_node_ends(1, k) = EdgeKeyHigh(key);
    edge_nodes.col(k) = nodes.col(middle);
    ++k;
  }
  KeepNodes(keep);
}

void Mesh::Transform(double scale, const Vec3& translate) {
  nodes = (scale * nodes).colwise() + translate;
  edge_nodes = (scale * edge_nodes).colwise() + translate;
}

}  // namespace gipsi
