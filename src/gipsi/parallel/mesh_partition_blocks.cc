/// @file
/// Partitioning a mesh that no rank holds whole: the dual graph built from the ranks' blocks,
/// cut by PT-Scotch, and the tets, nodes, triangles and groups moved to their parts.
///
/// Every step is an all-to-all exchange of records, so each rank holds O(its block + its part)
/// and never the whole mesh:
///  1. each tet's four faces and each triangle go to the rank that a hash of their sorted nodes
///     names; there, a face met twice joins two tets (the dual graph's edges), which go back to
///     the tets' block ranks;
///  2. PT-Scotch cuts the graph, each rank giving the rows of its block of tets (the same graph,
///     in the same row and column order, as the whole mesh gave before: the same cut);
///  3. each tet goes to its part's rank; each rank asks the nodes its tets use from their block
///     ranks, which make the lowest asker the owner, number the owned nodes (a prefix sum per
///     owner) and send coordinates, owner, number and groups back;
///  4. a triangle goes to every part holding a tet it is a face of (found at the face's hash
///     rank from the tets' parts, asked from their block ranks).

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <numeric>
#include <tuple>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/mesh_partition_detail.h"

namespace gipsi {
namespace {

using detail::BlockRank;
using detail::Exchange;
using detail::FaceRank;
using detail::Received;

using Face = std::array<int, 3>;

// A tet's face (tag: the corner it is opposite, 0..3) or a triangle (tag -1), by sorted nodes.
struct FaceRecord {
  Face face;
  int item;  // whole-mesh tet or triangle index
  int tag;
};

// Tet `tet`'s face opposite `skip` is shared with tet `other`.
struct Adjacency {
  int tet, skip, other;
};

struct TetRecord {
  int tet;
  std::array<int, 4> nodes;
  std::int64_t id;  // Mesh::tet_ids entry (0 without ids)
};

struct NodeRecord {
  int node;
  int owner;
  std::int64_t global;
  std::array<double, 3> x;
};

struct TriangleRecord {
  int triangle;
  std::array<int, 3> nodes;
};

// An item (whole-mesh index) in group `group` (its index in the block's group list).
struct Membership {
  int item, group;
};

Face SortedFace(const std::array<int, 4>& tet, int skip) {
  Face f{};
  int k = 0;
  for (int a = 0; a < 4; ++a)
    if (a != skip) f[static_cast<std::size_t>(k++)] = tet[static_cast<std::size_t>(a)];
  std::sort(f.begin(), f.end());
  return f;
}

std::array<int, 4> TetOf(const Tets& tets, Index e) {
  return {tets(0, e), tets(1, e), tets(2, e), tets(3, e)};
}

// Checks the blocks agree with each other and name nodes that exist.
void CheckBlocks(const MeshBlock& block, MPI_Comm comm) {
  std::array<std::int64_t, 3> mine{block.num_nodes, block.num_tets, block.num_triangles};
  std::array<std::int64_t, 3> low{}, high{};
  MPI_Allreduce(mine.data(), low.data(), 3, MPI_INT64_T, MPI_MIN, comm);
  MPI_Allreduce(mine.data(), high.data(), 3, MPI_INT64_T, MPI_MAX, comm);
  GIPSI_CHECK(low == high, "the ranks' mesh blocks disagree on the mesh's size");
  std::array<std::int64_t, 3> held{block.nodes.cols(), block.tets.cols(), block.triangles.cols()},
      total{};
  MPI_Allreduce(held.data(), total.data(), 3, MPI_INT64_T, MPI_SUM, comm);
  GIPSI_CHECK(total == mine, "the ranks' mesh blocks do not cover the mesh");
  if (block.num_nodes > std::numeric_limits<int>::max() ||
      block.num_tets > std::numeric_limits<int>::max() ||
      block.num_triangles > std::numeric_limits<int>::max())
    throw InputError(fmt::format(
        "a mesh of {} nodes and {} tets is more than the partitioner's 32-bit indices hold",
        block.num_nodes, block.num_tets));
  auto in_range = [&](const auto& connectivity) {
    return connectivity.size() == 0 ||
           (connectivity.minCoeff() >= 0 && connectivity.maxCoeff() < block.num_nodes);
  };
  int bad = in_range(block.tets) && in_range(block.triangles) ? 0 : 1, any = 0;
  MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, comm);
  if (any != 0)
    throw InputError(
        fmt::format("a tet or triangle names a node outside the mesh's {} nodes", block.num_nodes));
}

}  // namespace

MeshPart PartitionMeshBlocks(const MeshBlock& block, MPI_Comm comm) {
  MeshPart out;
  MPI_Comm_rank(comm, &out.rank);
  MPI_Comm_size(comm, &out.size);
  GIPSI_CHECK(block.rank == out.rank && block.size == out.size,
              "a mesh block was made for another rank or rank count");
  CheckBlocks(block, comm);
  const int rank = out.rank, size = out.size;
  const auto num_nodes = static_cast<int>(block.num_nodes);
  const auto num_tets = static_cast<int>(block.num_tets);
  if (num_tets < size)
    throw InputError(
        fmt::format("a mesh of {} tets cannot be split over {} ranks", num_tets, size));
  const auto tet_begin = static_cast<int>(block.tet_begin());
  const auto local_tets = static_cast<int>(block.tets.cols());
  const auto node_begin = static_cast<int>(block.node_begin());
  const auto first_triangle = static_cast<int>(block.first_triangle);
  const auto usize = static_cast<std::size_t>(size);

  // 1. Faces meet at their hash rank; a face met by two tets is a dual-graph edge.
  std::vector<std::vector<FaceRecord>> to(usize);
  for (int e = 0; e < local_tets; ++e) {
    const auto tet = TetOf(block.tets, e);
    for (int skip = 0; skip < 4; ++skip) {
      const Face f = SortedFace(tet, skip);
      to[static_cast<std::size_t>(FaceRank(f, size))].push_back({f, tet_begin + e, skip});
    }
  }
  for (Index t = 0; t < block.triangles.cols(); ++t) {
    Face f{block.triangles(0, t), block.triangles(1, t), block.triangles(2, t)};
    std::sort(f.begin(), f.end());
    to[static_cast<std::size_t>(FaceRank(f, size))].push_back(
        {f, first_triangle + static_cast<int>(t), -1});
  }
  Received<FaceRecord> faces = Exchange(to, comm);
  // Sorted by face, the triangles first, then the tets by index: consecutive tets on one face
  // are neighbours (as the whole mesh's sorted face list paired them).
  std::sort(faces.items.begin(), faces.items.end(), [](const FaceRecord& a, const FaceRecord& b) {
    if (a.face != b.face) return a.face < b.face;
    if ((a.tag < 0) != (b.tag < 0)) return a.tag < 0;
    return a.item < b.item;
  });
  std::vector<std::vector<Adjacency>> adjacency(usize);
  // Triangles and the tets they are a face of, resolved to parts once the cut is known.
  std::vector<std::pair<int, int>> triangle_tet;  // (triangle, tet)
  for (std::size_t i = 0; i < faces.items.size();) {
    std::size_t j = i;
    while (j < faces.items.size() && faces.items[j].face == faces.items[i].face) ++j;
    std::size_t first_tet = i;
    while (first_tet < j && faces.items[first_tet].tag < 0) ++first_tet;
    for (std::size_t k = first_tet; k + 1 < j; ++k) {
      const FaceRecord &a = faces.items[k], &b = faces.items[k + 1];
      adjacency[static_cast<std::size_t>(BlockRank(a.item, num_tets, size))].push_back(
          {a.item, a.tag, b.item});
      adjacency[static_cast<std::size_t>(BlockRank(b.item, num_tets, size))].push_back(
          {b.item, b.tag, a.item});
    }
    for (std::size_t t = i; t < first_tet; ++t)
      for (std::size_t k = first_tet; k < j; ++k)
        triangle_tet.emplace_back(faces.items[t].item, faces.items[k].item);
    i = j;
  }
  faces = {};
  Received<Adjacency> edges = Exchange(adjacency, comm);
  adjacency = {};

  // 2. The graph's rows of this block: each tet's neighbours in the order of its faces' nodes,
  // at most four (the whole mesh's sorted face list gave them in that order).
  struct Neighbour {
    int tet;  // local
    Face face;
    int other;
    bool operator<(const Neighbour& o) const {
      return std::tie(tet, face, other) < std::tie(o.tet, o.face, o.other);
    }
  };
  std::vector<Neighbour> around;
  around.reserve(edges.items.size());
  for (const Adjacency& a : edges.items) {
    const int e = a.tet - tet_begin;
    around.push_back({e, SortedFace(TetOf(block.tets, e), a.skip), a.other});
  }
  edges = {};
  std::sort(around.begin(), around.end());
  std::vector<int> rows(static_cast<std::size_t>(local_tets) + 1, 0), columns;
  columns.reserve(4 * static_cast<std::size_t>(local_tets));
  for (std::size_t k = 0, taken = 0; k < around.size(); ++k) {
    taken = k > 0 && around[k - 1].tet == around[k].tet ? taken + 1 : 0;
    if (taken >= 4) continue;
    columns.push_back(around[k].other);
    ++rows[static_cast<std::size_t>(around[k].tet) + 1];
  }
  for (int e = 0; e < local_tets; ++e)
    rows[static_cast<std::size_t>(e) + 1] += rows[static_cast<std::size_t>(e)];
  around = {};
  const std::vector<int> part = detail::ScotchPart(rows, columns, comm, size);
  rows = {};
  columns = {};

  // 3. Tets to their parts, with their ids and groups.
  // Each kind's memberships of this block, sorted by item (then group).
  std::vector<Membership> tet_groups_of, node_groups_of, triangle_groups_of;
  for (std::size_t g = 0; g < block.groups.size(); ++g) {
    const MeshGroup& group = block.groups[g];
    auto& list = group.dim == 0   ? node_groups_of
                 : group.dim == 2 ? triangle_groups_of
                                  : tet_groups_of;
    const int begin = group.dim == 0 ? node_begin : group.dim == 2 ? first_triangle : tet_begin;
    const Index count = group.dim == 0   ? block.nodes.cols()
                        : group.dim == 2 ? block.triangles.cols()
                                         : local_tets;
    for (int item : group.items) {
      GIPSI_CHECK(item >= begin && item - begin < count,
                  "a block's group lists an item outside the block");
      list.push_back({item, static_cast<int>(g)});
    }
  }
  for (auto* list : {&tet_groups_of, &node_groups_of, &triangle_groups_of})
    std::sort(list->begin(), list->end(), [](const Membership& a, const Membership& b) {
      return std::tie(a.item, a.group) < std::tie(b.item, b.group);
    });
  // The memberships of `item` among a sorted list.
  auto memberships = [](const std::vector<Membership>& list, int item) {
    const auto first = std::lower_bound(list.begin(), list.end(), item,
                                        [](const Membership& m, int i) { return m.item < i; });
    auto last = first;
    while (last != list.end() && last->item == item) ++last;
    return std::pair{first, last};
  };
  std::vector<std::vector<TetRecord>> tets_to(usize);
  std::vector<std::vector<Membership>> memberships_to(usize);
  for (int e = 0; e < local_tets; ++e) {
    const auto p = static_cast<std::size_t>(part[static_cast<std::size_t>(e)]);
    tets_to[p].push_back({tet_begin + e, TetOf(block.tets, e),
                          block.tet_ids.empty() ? 0 : block.tet_ids[static_cast<std::size_t>(e)]});
    const auto [first, last] = memberships(tet_groups_of, tet_begin + e);
    memberships_to[p].insert(memberships_to[p].end(), first, last);
  }
  tet_groups_of = {};
  std::vector<TetRecord> my_tets = Exchange(tets_to, comm).items;
  tets_to = {};
  std::vector<Membership> my_tet_groups = Exchange(memberships_to, comm).items;
  // Blocks are in rank order and each sends its tets in order: already in whole-mesh order.
  GIPSI_CHECK(std::is_sorted(my_tets.begin(), my_tets.end(),
                             [](const TetRecord& a, const TetRecord& b) { return a.tet < b.tet; }));

  // Nodes: ask each used node from its block rank.
  std::vector<int> used;
  used.reserve(4 * my_tets.size());
  for (const TetRecord& t : my_tets) used.insert(used.end(), t.nodes.begin(), t.nodes.end());
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  std::vector<std::vector<int>> asks(usize);
  for (int n : used) asks[static_cast<std::size_t>(BlockRank(n, num_nodes, size))].push_back(n);
  const Received<int> asked = Exchange(asks, comm);
  asks = {};
  // The owner of each node of this block: the lowest rank that asked (rank 0 for a node no tet
  // uses); then its number: the owner's first number, plus its nodes in lower blocks, plus its
  // nodes before this one in this block.
  const auto block_nodes = static_cast<std::size_t>(block.nodes.cols());
  std::vector<int> owner(block_nodes, std::numeric_limits<int>::max());
  {
    std::size_t k = 0;
    for (int from = 0; from < size; ++from)
      for (int c = 0; c < asked.counts[static_cast<std::size_t>(from)]; ++c, ++k) {
        int& o = owner[static_cast<std::size_t>(asked.items[k] - node_begin)];
        o = std::min(o, from);
      }
  }
  std::vector<std::int64_t> owned_here(usize, 0), owned_before(usize, 0), owned_total(usize, 0);
  for (int& o : owner) {
    if (o == std::numeric_limits<int>::max()) o = 0;
    ++owned_here[static_cast<std::size_t>(o)];
  }
  MPI_Exscan(owned_here.data(), owned_before.data(), size, MPI_INT64_T, MPI_SUM, comm);
  if (rank == 0) std::fill(owned_before.begin(), owned_before.end(), 0);
  MPI_Allreduce(owned_here.data(), owned_total.data(), size, MPI_INT64_T, MPI_SUM, comm);
  std::vector<std::int64_t> first(usize + 1, 0);
  std::partial_sum(owned_total.begin(), owned_total.end(), first.begin() + 1);
  std::vector<std::int64_t> global(block_nodes);
  {
    std::vector<std::int64_t> next(usize);
    for (std::size_t r = 0; r < usize; ++r) next[r] = first[r] + owned_before[r];
    for (std::size_t n = 0; n < block_nodes; ++n)
      global[n] = next[static_cast<std::size_t>(owner[n])]++;
  }
  std::vector<std::vector<NodeRecord>> nodes_to(usize);
  std::vector<std::vector<Membership>> node_memberships_to(usize);
  auto send_node = [&](std::size_t r, int n) {
    const auto i = static_cast<std::size_t>(n - node_begin);
    const auto col = static_cast<Index>(i);
    nodes_to[r].push_back(
        {n, owner[i], global[i], {block.nodes(0, col), block.nodes(1, col), block.nodes(2, col)}});
    const auto [first, last] = memberships(node_groups_of, n);
    node_memberships_to[r].insert(node_memberships_to[r].end(), first, last);
  };
  {
    std::vector<unsigned char> was_asked(block_nodes, 0);
    std::size_t k = 0;
    for (int from = 0; from < size; ++from)
      for (int c = 0; c < asked.counts[static_cast<std::size_t>(from)]; ++c, ++k) {
        send_node(static_cast<std::size_t>(from), asked.items[k]);
        was_asked[static_cast<std::size_t>(asked.items[k] - node_begin)] = 1;
      }
    for (std::size_t n = 0; n < block_nodes; ++n)
      if (was_asked[n] == 0) send_node(0, node_begin + static_cast<int>(n));
  }
  node_groups_of = {};
  std::vector<NodeRecord> my_nodes = Exchange(nodes_to, comm).items;
  nodes_to = {};
  std::vector<Membership> my_node_groups = Exchange(node_memberships_to, comm).items;
  node_memberships_to = {};

  // 4. Triangles: the parts of the tets each is a face of, asked from the tets' block ranks.
  std::vector<std::vector<int>> part_asks(usize);
  for (const auto& [triangle, tet] : triangle_tet)
    part_asks[static_cast<std::size_t>(BlockRank(tet, num_tets, size))].push_back(tet);
  const Received<int> part_asked = Exchange(part_asks, comm);
  part_asks = {};
  std::vector<std::vector<int>> part_replies(usize);
  {
    std::size_t k = 0;
    for (int from = 0; from < size; ++from)
      for (int c = 0; c < part_asked.counts[static_cast<std::size_t>(from)]; ++c, ++k)
        part_replies[static_cast<std::size_t>(from)].push_back(
            part[static_cast<std::size_t>(part_asked.items[k] - tet_begin)]);
  }
  const Received<int> tet_parts = Exchange(part_replies, comm);
  part_replies = {};
  // The replies come back in the order asked: per block rank, in triangle_tet's order.
  std::vector<std::pair<int, int>> triangle_part;  // (triangle, part)
  {
    std::vector<std::size_t> next(usize, 0), start(usize, 0);
    for (std::size_t r = 1; r < usize; ++r)
      start[r] = start[r - 1] + static_cast<std::size_t>(tet_parts.counts[r - 1]);
    for (const auto& [triangle, tet] : triangle_tet) {
      const auto r = static_cast<std::size_t>(BlockRank(tet, num_tets, size));
      triangle_part.emplace_back(triangle, tet_parts.items[start[r] + next[r]++]);
    }
  }
  triangle_tet = {};
  std::sort(triangle_part.begin(), triangle_part.end());
  triangle_part.erase(std::unique(triangle_part.begin(), triangle_part.end()), triangle_part.end());
  // Each triangle's parts go to its block rank, which sends it there with its groups.
  std::vector<std::int64_t> firsts(usize);
  std::int64_t mine = block.first_triangle;
  MPI_Allgather(&mine, 1, MPI_INT64_T, firsts.data(), 1, MPI_INT64_T, comm);
  std::vector<std::vector<std::array<int, 2>>> destinations_to(usize);
  for (const auto& tp : triangle_part) {
    const auto holder = static_cast<std::size_t>(
        std::upper_bound(firsts.begin(), firsts.end(), static_cast<std::int64_t>(tp.first)) -
        firsts.begin() - 1);
    destinations_to[holder].push_back({tp.first, tp.second});
  }
  triangle_part = {};
  const std::vector<std::array<int, 2>> destinations = Exchange(destinations_to, comm).items;
  destinations_to = {};
  std::vector<std::vector<TriangleRecord>> triangles_to(usize);
  std::vector<std::vector<Membership>> triangle_memberships_to(usize);
  for (const auto& [triangle, p] : destinations) {
    const auto t = static_cast<std::size_t>(triangle - first_triangle);
    const auto col = static_cast<Index>(t);
    triangles_to[static_cast<std::size_t>(p)].push_back(
        {triangle, {block.triangles(0, col), block.triangles(1, col), block.triangles(2, col)}});
    const auto [first, last] = memberships(triangle_groups_of, triangle);
    triangle_memberships_to[static_cast<std::size_t>(p)].insert(
        triangle_memberships_to[static_cast<std::size_t>(p)].end(), first, last);
  }
  triangle_groups_of = {};
  std::vector<TriangleRecord> my_triangles = Exchange(triangles_to, comm).items;
  triangles_to = {};
  std::vector<Membership> my_triangle_groups = Exchange(triangle_memberships_to, comm).items;
  std::sort(
      my_triangles.begin(), my_triangles.end(),
      [](const TriangleRecord& a, const TriangleRecord& b) { return a.triangle < b.triangle; });

  // The part: owned nodes then shared ones, each in whole-mesh order; tets and triangles in
  // whole-mesh order; groups in the block's order, items local and sorted.
  std::stable_partition(my_nodes.begin(), my_nodes.end(),
                        [&](const NodeRecord& n) { return n.owner == rank; });
  auto by_node = [](const NodeRecord& a, const NodeRecord& b) { return a.node < b.node; };
  const auto first_shared = std::find_if(my_nodes.begin(), my_nodes.end(),
                                         [&](const NodeRecord& n) { return n.owner != rank; });
  std::sort(my_nodes.begin(), first_shared, by_node);
  std::sort(first_shared, my_nodes.end(), by_node);
  out.num_owned = first_shared - my_nodes.begin();
  out.first_owned = first[static_cast<std::size_t>(rank)];
  out.num_global_nodes = num_nodes;
  out.num_global_tets = num_tets;
  auto mesh = std::make_shared<Mesh>();
  mesh->nodes.resize(3, static_cast<Index>(my_nodes.size()));
  std::vector<std::pair<int, int>> local_of;  // (whole node, local node), sorted
  local_of.reserve(my_nodes.size());
  for (std::size_t i = 0; i < my_nodes.size(); ++i) {
    const NodeRecord& n = my_nodes[i];
    out.whole_node.push_back(n.node);
    out.global.push_back(n.global);
    for (int a = 0; a < 3; ++a)
      mesh->nodes(a, static_cast<Index>(i)) = n.x[static_cast<std::size_t>(a)];
    local_of.emplace_back(n.node, static_cast<int>(i));
  }
  std::sort(local_of.begin(), local_of.end());
  auto local_node = [&](int whole) {
    const auto it = std::lower_bound(local_of.begin(), local_of.end(), std::pair{whole, -1});
    GIPSI_CHECK(it != local_of.end() && it->first == whole, "a part's node was not received");
    return it->second;
  };
  auto local_index = [](const std::vector<int>& sorted, int whole) {
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), whole);
    return it != sorted.end() && *it == whole ? static_cast<int>(it - sorted.begin()) : -1;
  };
  mesh->tets.resize(4, static_cast<Index>(my_tets.size()));
  for (std::size_t e = 0; e < my_tets.size(); ++e) {
    out.whole_tet.push_back(my_tets[e].tet);
    for (int a = 0; a < 4; ++a)
      mesh->tets(a, static_cast<Index>(e)) =
          local_node(my_tets[e].nodes[static_cast<std::size_t>(a)]);
  }
  if (!block.tet_ids.empty()) {
    for (const TetRecord& t : my_tets) mesh->tet_ids.push_back(t.id);
    mesh->tet_id_kind = block.tet_id_kind;
  }
  std::vector<int> whole_triangle;
  mesh->triangles.resize(3, static_cast<Index>(my_triangles.size()));
  for (std::size_t t = 0; t < my_triangles.size(); ++t) {
    whole_triangle.push_back(my_triangles[t].triangle);
    for (int a = 0; a < 3; ++a)
      mesh->triangles(a, static_cast<Index>(t)) =
          local_node(my_triangles[t].nodes[static_cast<std::size_t>(a)]);
  }
  for (const MeshGroup& group : block.groups) mesh->groups.push_back({group.name, group.dim, {}});
  for (const Membership& m : my_node_groups)
    mesh->groups[static_cast<std::size_t>(m.group)].items.push_back(local_node(m.item));
  for (const Membership& m : my_tet_groups)
    mesh->groups[static_cast<std::size_t>(m.group)].items.push_back(
        local_index(out.whole_tet, m.item));
  for (const Membership& m : my_triangle_groups)
    mesh->groups[static_cast<std::size_t>(m.group)].items.push_back(
        local_index(whole_triangle, m.item));
  for (MeshGroup& g : mesh->groups) {
    std::sort(g.items.begin(), g.items.end());
    g.items.erase(std::unique(g.items.begin(), g.items.end()), g.items.end());
  }
  out.mesh = std::move(mesh);
  return out;
}

}  // namespace gipsi
