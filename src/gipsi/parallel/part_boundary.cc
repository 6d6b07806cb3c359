/// @file
/// The whole mesh's boundary on one rank's part, found without the whole mesh
/// (mesh_partition.h: PartBoundary).

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <variant>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/mesh_partition_detail.h"

namespace gipsi {

namespace {

using Face = std::array<int, 3>;

// A face of a local tet that no other local tet shares, by its sorted whole-mesh nodes.
struct FaceRecord {
  Face face;
};

// Answers, in the order they came, whether each record's face came twice (from two ranks: a
// face between two parts, so not on the whole mesh's boundary).
std::vector<std::vector<char>> MatchedTwice(const detail::Received<FaceRecord>& got, int size) {
  std::vector<std::size_t> order(got.items.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&got](std::size_t a, std::size_t b) { return got.items[a].face < got.items[b].face; });
  std::vector<char> twice(got.items.size(), 0);
  for (std::size_t i = 0; i + 1 < order.size(); ++i)
    if (got.items[order[i]].face == got.items[order[i + 1]].face)
      twice[order[i]] = twice[order[i + 1]] = 1;
  std::vector<std::vector<char>> reply(static_cast<std::size_t>(size));
  std::size_t k = 0;
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < got.counts[static_cast<std::size_t>(r)]; ++c)
      reply[static_cast<std::size_t>(r)].push_back(twice[k++]);
  return reply;
}

// Each key's position among the distinct keys of every rank, ascending (a key may come from
// several ranks, or twice from one), and how many distinct keys there are. Keys lie in
// [0, count); each is ranked at its block rank (BlockRank is increasing in the key, so a block
// rank's offset is the number of distinct keys of the blocks before it).
std::vector<int> RankAmongAll(std::span<const std::int64_t> keys, std::int64_t count, MPI_Comm comm,
                              std::int64_t& distinct_total) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  std::vector<std::vector<std::int64_t>> to(static_cast<std::size_t>(size));
  std::vector<int> sent_to(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const int rank = detail::BlockRank(keys[i], count, size);
    sent_to[i] = rank;
    to[static_cast<std::size_t>(rank)].push_back(keys[i]);
  }
  const auto got = detail::Exchange(to, comm);
  std::vector<std::int64_t> distinct = got.items;
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  const auto mine = static_cast<std::int64_t>(distinct.size());
  std::int64_t offset = 0;
  MPI_Exscan(&mine, &offset, 1, MPI_INT64_T, MPI_SUM, comm);
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  if (rank == 0) offset = 0;  // MPI_Exscan leaves rank 0's result undefined
  MPI_Allreduce(&mine, &distinct_total, 1, MPI_INT64_T, MPI_SUM, comm);
  GIPSI_CHECK(distinct_total < std::int64_t{1} << 31, "more than 2^31 - 1 boundary items");
  std::vector<std::vector<int>> reply(static_cast<std::size_t>(size));
  std::size_t k = 0;
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < got.counts[static_cast<std::size_t>(r)]; ++c, ++k)
      reply[static_cast<std::size_t>(r)].push_back(static_cast<int>(
          offset +
          (std::lower_bound(distinct.begin(), distinct.end(), got.items[k]) - distinct.begin())));
  const auto answers = detail::Exchange(reply, comm);
  // The answers come per rank in the order sent.
  std::vector<std::size_t> next(static_cast<std::size_t>(size), 0);
  for (int r = 1; r < size; ++r)
    next[static_cast<std::size_t>(r)] =
        next[static_cast<std::size_t>(r - 1)] +
        static_cast<std::size_t>(answers.counts[static_cast<std::size_t>(r - 1)]);
  std::vector<int> out(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i)
    out[i] = answers.items[next[static_cast<std::size_t>(sent_to[i])]++];
  return out;
}

}  // namespace

WholeBoundaryNumbers NumberOnWholeBoundary(const MeshPart& part, const BoundarySurface& boundary,
                                           MPI_Comm comm) {
  const Mesh& mesh = *part.mesh;
  std::vector<std::int64_t> keys;
  keys.reserve(boundary.vertex_to_node.size());
  for (const int node : boundary.vertex_to_node)
    keys.push_back(part.whole_node[static_cast<std::size_t>(node)]);
  WholeBoundaryNumbers out;
  out.vertex = RankAmongAll(keys, part.num_global_nodes, comm, out.whole_vertices);
  // A face's key: its tet's whole index, then the tet's local node it is opposite to.
  keys.clear();
  for (Index f = 0; f < boundary.num_triangles(); ++f) {
    const int tet = boundary.face_to_tet[static_cast<std::size_t>(f)];
    int opposite = -1;
    for (int k = 0; k < 4; ++k) {
      const int node = mesh.tets(k, tet);
      bool on_face = false;
      for (int a = 0; a < 3; ++a)
        on_face =
            on_face ||
            boundary.vertex_to_node[static_cast<std::size_t>(boundary.triangles(a, f))] == node;
      if (!on_face) opposite = k;
    }
    GIPSI_CHECK(opposite >= 0, "boundary face {} is not a face of its tet", f);
    keys.push_back(4 * static_cast<std::int64_t>(part.whole_tet[static_cast<std::size_t>(tet)]) +
                   opposite);
  }
  out.face = RankAmongAll(keys, 4 * part.num_global_tets, comm, out.whole_faces);
  return out;
}

BoundarySurface PartBoundary(const MeshPart& part, MPI_Comm comm) {
  const Mesh& mesh = *part.mesh;
  const int size = part.size;
  // The faces no local tet shares (outward, in the order of their tets): the whole mesh's
  // boundary faces of local tets, and the faces between this part and others.
  const BoundarySurface local = ExtractTetBoundary(mesh.nodes, mesh.tets);
  auto whole_node_of_vertex = [&](int vertex) {
    return part.whole_node[static_cast<std::size_t>(
        local.vertex_to_node[static_cast<std::size_t>(vertex)])];
  };
  // 1. Each such face meets its copy, if another part has one, at the rank its nodes hash to.
  std::vector<std::vector<FaceRecord>> to(static_cast<std::size_t>(size));
  std::vector<int> sent_to(static_cast<std::size_t>(local.num_triangles()));
  for (Index f = 0; f < local.num_triangles(); ++f) {
    Face face;
    for (int a = 0; a < 3; ++a)
      face[static_cast<std::size_t>(a)] = whole_node_of_vertex(local.triangles(a, f));
    std::sort(face.begin(), face.end());
    const int rank = detail::FaceRank(face, size);
    sent_to[static_cast<std::size_t>(f)] = rank;
    to[static_cast<std::size_t>(rank)].push_back({face});
  }
  const auto answers = detail::Exchange(MatchedTwice(detail::Exchange(to, comm), size), comm);
  // The answers come per rank in the order sent.
  std::vector<std::size_t> next(static_cast<std::size_t>(size), 0),
      first(static_cast<std::size_t>(size), 0);
  for (int r = 1; r < size; ++r)
    first[static_cast<std::size_t>(r)] =
        first[static_cast<std::size_t>(r - 1)] +
        static_cast<std::size_t>(answers.counts[static_cast<std::size_t>(r - 1)]);
  std::vector<Index> kept;
  for (Index f = 0; f < local.num_triangles(); ++f) {
    const auto r = static_cast<std::size_t>(sent_to[static_cast<std::size_t>(f)]);
    if (answers.items[first[r] + next[r]++] == 0) kept.push_back(f);
  }

  // 2. The whole boundary's nodes: those of the kept faces, told to each node's block rank;
  // every local node then asks its block rank whether it is one (a node may touch the boundary
  // on another part only).
  const std::int64_t nodes = part.num_global_nodes;
  std::vector<std::vector<int>> on_boundary(static_cast<std::size_t>(size));
  for (const Index f : kept)
    for (int a = 0; a < 3; ++a) {
      const int w = whole_node_of_vertex(local.triangles(a, f));
      on_boundary[static_cast<std::size_t>(detail::BlockRank(w, nodes, size))].push_back(w);
    }
  for (auto& list : on_boundary) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  auto marked = detail::Exchange(on_boundary, comm).items;
  std::sort(marked.begin(), marked.end());
  std::vector<std::vector<int>> asked(static_cast<std::size_t>(size));
  for (const int w : part.whole_node)
    asked[static_cast<std::size_t>(detail::BlockRank(w, nodes, size))].push_back(w);
  const auto questions = detail::Exchange(asked, comm);
  std::vector<std::vector<char>> replies(static_cast<std::size_t>(size));
  std::size_t k = 0;
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < questions.counts[static_cast<std::size_t>(r)]; ++c, ++k)
      replies[static_cast<std::size_t>(r)].push_back(
          std::binary_search(marked.begin(), marked.end(), questions.items[k]) ? 1 : 0);
  const auto flags = detail::Exchange(replies, comm);

  // 3. The part's boundary: every local node on the whole boundary a vertex (local order), the
  // kept faces in their order.
  std::fill(next.begin(), next.end(), 0);
  for (int r = 1; r < size; ++r)
    first[static_cast<std::size_t>(r)] =
        first[static_cast<std::size_t>(r - 1)] +
        static_cast<std::size_t>(flags.counts[static_cast<std::size_t>(r - 1)]);
  BoundarySurface out;
  std::vector<int> vertex_of_node(part.whole_node.size(), -1);
  for (std::size_t i = 0; i < part.whole_node.size(); ++i) {
    const auto r = static_cast<std::size_t>(detail::BlockRank(part.whole_node[i], nodes, size));
    if (flags.items[first[r] + next[r]++] == 0) continue;
    vertex_of_node[i] = static_cast<int>(out.vertex_to_node.size());
    out.vertex_to_node.push_back(static_cast<int>(i));
  }
  out.triangles.resize(3, static_cast<Index>(kept.size()));
  out.face_to_tet.reserve(kept.size());
  for (std::size_t j = 0; j < kept.size(); ++j) {
    for (int a = 0; a < 3; ++a)
      out.triangles(a, static_cast<Index>(j)) = vertex_of_node[static_cast<std::size_t>(
          local.vertex_to_node[static_cast<std::size_t>(local.triangles(a, kept[j]))])];
    out.face_to_tet.push_back(local.face_to_tet[static_cast<std::size_t>(kept[j])]);
  }
  return out;
}

std::vector<int> BoundaryVerticesOfNodes(const BoundarySurface& boundary,
                                         std::span<const int> nodes) {
  std::vector<int> vertices;
  for (Index v = 0; v < boundary.num_vertices(); ++v)
    if (std::binary_search(nodes.begin(), nodes.end(),
                           boundary.vertex_to_node[static_cast<std::size_t>(v)]))
      vertices.push_back(static_cast<int>(v));
  return vertices;
}

std::vector<int> SelectPartBoundaryFaces(const Region& region, const MeshPart& part,
                                         const BoundarySurface& boundary, double tolerance,
                                         MPI_Comm comm) {
  // Collective for every region: the nodes first, on every rank.
  const std::vector<int> vertices =
      BoundaryVerticesOfNodes(boundary, SelectPartNodes(region, part, tolerance, comm));
  // A triangle group's faces are matched to the part's (every face of a local tet has its
  // triangles here); otherwise a face is selected when its three vertices are, as on the
  // whole mesh.
  const auto* group_region = std::get_if<GroupRegion>(&region);
  const MeshGroup* group =
      group_region != nullptr ? part.mesh->FindGroup(group_region->name) : nullptr;
  if (group != nullptr && group->dim == 2) return SelectBoundaryFaces(region, *part.mesh, boundary);
  std::vector<char> selected(static_cast<std::size_t>(boundary.num_vertices()), 0);
  for (const int v : vertices) selected[static_cast<std::size_t>(v)] = 1;
  std::vector<int> faces;
  for (Index f = 0; f < boundary.num_triangles(); ++f)
    if (selected[static_cast<std::size_t>(boundary.triangles(0, f))] != 0 &&
        selected[static_cast<std::size_t>(boundary.triangles(1, f))] != 0 &&
        selected[static_cast<std::size_t>(boundary.triangles(2, f))] != 0)
      faces.push_back(static_cast<int>(f));
  return faces;
}

}  // namespace gipsi
