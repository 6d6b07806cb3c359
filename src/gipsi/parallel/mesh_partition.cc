/// @file
/// Graph partitioning of tet meshes (PT-Scotch through PETSc) and the parts' numbering.

#include "gipsi/parallel/mesh_partition.h"

#include <fmt/format.h>
#include <stdio.h>  // NOLINT(modernize-deprecated-headers): ptscotch.h needs FILE declared

#include <scotch/ptscotch.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>
#include <numeric>

#include "gipsi/base/error.h"

namespace gipsi {
namespace {

using Face = std::array<int, 3>;

constexpr SCOTCH_Num kScotchSeed = 20041;  // any fixed number
static_assert(sizeof(SCOTCH_Num) == sizeof(int), "the parts are gathered as MPI_INT");

// The face of tet e opposite its corner `skip`, nodes sorted.
Face SortedFace(const Tets& tets, Index e, int skip) {
  Face f{};
  int k = 0;
  for (int a = 0; a < 4; ++a)
    if (a != skip) f[static_cast<std::size_t>(k++)] = tets(a, e);
  std::sort(f.begin(), f.end());
  return f;
}

// The face-adjacency (dual) graph's neighbours of every tet: up to four tets each.
std::vector<std::array<int, 4>> FaceNeighbours(const Tets& tets) {
  const Index count = tets.cols();
  struct Entry {
    Face face;
    int tet;
  };
  std::vector<Entry> faces;
  faces.reserve(static_cast<std::size_t>(4 * count));
  for (Index e = 0; e < count; ++e)
    for (int skip = 0; skip < 4; ++skip)
      faces.push_back({SortedFace(tets, e, skip), static_cast<int>(e)});
  std::sort(faces.begin(), faces.end(), [](const Entry& a, const Entry& b) {
    return a.face != b.face ? a.face < b.face : a.tet < b.tet;
  });
  std::vector<std::array<int, 4>> neighbours(static_cast<std::size_t>(count), {-1, -1, -1, -1});
  auto add = [&](int e, int other) {
    for (int& slot : neighbours[static_cast<std::size_t>(e)])
      if (slot < 0) {
        slot = other;
        return;
      }
  };
  for (std::size_t i = 0; i + 1 < faces.size(); ++i)
    if (faces[i].face == faces[i + 1].face) {
      add(faces[i].tet, faces[i + 1].tet);
      add(faces[i + 1].tet, faces[i].tet);
    }
  return neighbours;
}

// PT-Scotch's calls return 0 on success.
void Scotch(int code, const char* what) {
  if (code != 0)
    throw std::runtime_error(fmt::format("PT-Scotch failed in {} (error {})", what, code));
}

// The rank of every tet (identical on every rank): PT-Scotch on the dual graph, each rank
// giving the graph's rows for one contiguous block of tets. Called directly rather than through
// PETSc's MatPartitioning, which cannot ask for Scotch's deterministic mode: Debian builds
// Scotch with threads, and its default mode cut the same mesh differently in every call.
std::vector<int> PartitionTets(const Mesh& whole, MPI_Comm comm, int rank, int size) {
  if (whole.num_tets() > std::numeric_limits<SCOTCH_Num>::max())
    throw InputError(fmt::format("a mesh of {} tets is more than this Scotch build can cut ({})",
                                 whole.num_tets(), std::numeric_limits<SCOTCH_Num>::max()));
  const auto count = static_cast<SCOTCH_Num>(whole.num_tets());
  std::vector<int> part(static_cast<std::size_t>(count), 0);
  if (size == 1) return part;
  const auto neighbours = FaceNeighbours(whole.tets);
  const SCOTCH_Num begin = static_cast<SCOTCH_Num>(std::int64_t{count} * rank / size);
  const SCOTCH_Num end = static_cast<SCOTCH_Num>(std::int64_t{count} * (rank + 1) / size);
  std::vector<SCOTCH_Num> rows(static_cast<std::size_t>(end - begin) + 1, 0), columns;
  columns.reserve(4 * static_cast<std::size_t>(end - begin));
  for (SCOTCH_Num e = begin; e < end; ++e) {
    for (int other : neighbours[static_cast<std::size_t>(e)])
      if (other >= 0) columns.push_back(other);
    rows[static_cast<std::size_t>(e - begin) + 1] = static_cast<SCOTCH_Num>(columns.size());
  }
  const SCOTCH_Num local = end - begin, edges = rows.back();
  std::vector<SCOTCH_Num> block(static_cast<std::size_t>(local) + 1, 0);
  SCOTCH_Dgraph graph, bound;
  SCOTCH_Context context;
  SCOTCH_Strat strategy;
  Scotch(SCOTCH_dgraphInit(&graph, comm), "SCOTCH_dgraphInit");
  Scotch(SCOTCH_contextInit(&context), "SCOTCH_contextInit");
  SCOTCH_stratInit(&strategy);
  int code = SCOTCH_dgraphBuild(&graph, 0, local, local, rows.data(), nullptr, nullptr, nullptr,
                                edges, edges, columns.data(), nullptr, nullptr);
  const char* failed = code != 0 ? "SCOTCH_dgraphBuild" : nullptr;
  bool bound_graph = false;
  if (code == 0) {
    // Deterministic threads and a fixed random seed: the same mesh is cut the same way on the
    // same rank count in every run (a checkpoint restores only on the cut that wrote it).
    SCOTCH_contextOptionSetNum(&context, SCOTCH_OPTIONNUMDETERMINISTIC, 1);
    SCOTCH_contextOptionSetNum(&context, SCOTCH_OPTIONNUMRANDOMFIXEDSEED, 1);
    SCOTCH_contextRandomSeed(&context, kScotchSeed);
    code = SCOTCH_dgraphInit(&bound, comm);
    if (code == 0) code = SCOTCH_contextBindDgraph(&context, &graph, &bound);
    bound_graph = code == 0;
    if (code != 0) failed = "SCOTCH_contextBindDgraph";
  }
  if (code == 0) {
    // Scotch's default strategy, at most 1 % more tets than the mean on a rank (the settings
    // PETSc 3.18's MatPartitioning used, which the figures in docs/scale-out.md were taken with).
    code = SCOTCH_stratDgraphMapBuild(&strategy, SCOTCH_STRATDEFAULT, size, size, 0.01);
    if (code != 0) failed = "SCOTCH_stratDgraphMapBuild";
  }
  if (code == 0) {
    code = SCOTCH_dgraphPart(&bound, size, &strategy, block.data());
    if (code != 0) failed = "SCOTCH_dgraphPart";
  }
  if (bound_graph) SCOTCH_dgraphExit(&bound);
  SCOTCH_stratExit(&strategy);
  SCOTCH_contextExit(&context);
  SCOTCH_dgraphExit(&graph);
  if (failed != nullptr) Scotch(code, failed);
  std::vector<int> counts(static_cast<std::size_t>(size)), offsets(static_cast<std::size_t>(size));
  for (int r = 0; r < size; ++r) {
    offsets[static_cast<std::size_t>(r)] = static_cast<int>(std::int64_t{count} * r / size);
    counts[static_cast<std::size_t>(r)] =
        static_cast<int>(std::int64_t{count} * (r + 1) / size - std::int64_t{count} * r / size);
  }
  MPI_Allgatherv(block.data(), static_cast<int>(local), MPI_INT, part.data(), counts.data(),
                 offsets.data(), MPI_INT, comm);
  return part;
}

}  // namespace

MeshPart PartitionMesh(const Mesh& whole, MPI_Comm comm) {
  MeshPart out;
  MPI_Comm_rank(comm, &out.rank);
  MPI_Comm_size(comm, &out.size);
  const Index num_tets = whole.num_tets();
  const Index num_nodes = whole.num_nodes();
  if (num_tets < out.size)
    throw InputError(
        fmt::format("a mesh of {} tets cannot be split over {} ranks", num_tets, out.size));
  const std::vector<int> part = PartitionTets(whole, comm, out.rank, out.size);

  // Owner of each node: the lowest rank among its tets' (nodes in no tet go to rank 0).
  std::vector<int> owner(static_cast<std::size_t>(num_nodes), std::numeric_limits<int>::max());
  std::vector<unsigned char> used(static_cast<std::size_t>(num_nodes), 0);
  for (Index e = 0; e < num_tets; ++e)
    for (int a = 0; a < 4; ++a) {
      const auto n = static_cast<std::size_t>(whole.tets(a, e));
      owner[n] = std::min(owner[n], part[static_cast<std::size_t>(e)]);
      if (part[static_cast<std::size_t>(e)] == out.rank) used[n] = 1;
    }
  for (int& o : owner)
    if (o == std::numeric_limits<int>::max()) o = 0;
  std::vector<std::int64_t> first(static_cast<std::size_t>(out.size) + 1, 0);
  for (int o : owner) ++first[static_cast<std::size_t>(o) + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  std::vector<std::int64_t> global(static_cast<std::size_t>(num_nodes));
  {
    std::vector<std::int64_t> next(first.begin(), first.end() - 1);
    for (Index n = 0; n < num_nodes; ++n)
      global[static_cast<std::size_t>(n)] =
          next[static_cast<std::size_t>(owner[static_cast<std::size_t>(n)])]++;
  }
  out.first_owned = first[static_cast<std::size_t>(out.rank)];
  out.num_owned = first[static_cast<std::size_t>(out.rank) + 1] - out.first_owned;
  out.num_global_nodes = num_nodes;
  out.num_global_tets = num_tets;

  // Local nodes: the owned ones (including unused ones given to rank 0), then the shared ones.
  std::vector<int> local_of(static_cast<std::size_t>(num_nodes), -1);
  for (Index n = 0; n < num_nodes; ++n)
    if (owner[static_cast<std::size_t>(n)] == out.rank) {
      local_of[static_cast<std::size_t>(n)] = static_cast<int>(out.whole_node.size());
      out.whole_node.push_back(static_cast<int>(n));
    }
  for (Index n = 0; n < num_nodes; ++n)
    if (used[static_cast<std::size_t>(n)] && owner[static_cast<std::size_t>(n)] != out.rank) {
      local_of[static_cast<std::size_t>(n)] = static_cast<int>(out.whole_node.size());
      out.whole_node.push_back(static_cast<int>(n));
    }
  for (int n : out.whole_node) out.global.push_back(global[static_cast<std::size_t>(n)]);
  for (Index e = 0; e < num_tets; ++e)
    if (part[static_cast<std::size_t>(e)] == out.rank) out.whole_tet.push_back(static_cast<int>(e));

  auto mesh = std::make_shared<Mesh>();
  mesh->nodes.resize(3, static_cast<Index>(out.whole_node.size()));
  for (std::size_t i = 0; i < out.whole_node.size(); ++i)
    mesh->nodes.col(static_cast<Index>(i)) = whole.nodes.col(out.whole_node[i]);
  mesh->tets.resize(4, static_cast<Index>(out.whole_tet.size()));
  std::vector<int> local_tet(static_cast<std::size_t>(num_tets), -1);
  for (std::size_t e = 0; e < out.whole_tet.size(); ++e) {
    local_tet[static_cast<std::size_t>(out.whole_tet[e])] = static_cast<int>(e);
    for (int a = 0; a < 4; ++a)
      mesh->tets(a, static_cast<Index>(e)) =
          local_of[static_cast<std::size_t>(whole.tets(a, out.whole_tet[e]))];
  }
  if (!whole.tet_ids.empty()) {
    for (int e : out.whole_tet) mesh->tet_ids.push_back(whole.tet_ids[static_cast<std::size_t>(e)]);
    mesh->tet_id_kind = whole.tet_id_kind;
  }
  // Triangles that are a face of a local tet.
  std::vector<Face> local_faces;
  for (Index e = 0; e < mesh->num_tets(); ++e)
    for (int skip = 0; skip < 4; ++skip) local_faces.push_back(SortedFace(mesh->tets, e, skip));
  std::sort(local_faces.begin(), local_faces.end());
  std::vector<int> local_triangle(static_cast<std::size_t>(whole.num_triangles()), -1);
  std::vector<int> kept;
  for (Index t = 0; t < whole.num_triangles(); ++t) {
    Face f{};
    bool local = true;
    for (int a = 0; a < 3; ++a) {
      f[static_cast<std::size_t>(a)] = local_of[static_cast<std::size_t>(whole.triangles(a, t))];
      local = local && f[static_cast<std::size_t>(a)] >= 0;
    }
    if (!local) continue;
    Face sorted = f;
    std::sort(sorted.begin(), sorted.end());
    if (!std::binary_search(local_faces.begin(), local_faces.end(), sorted)) continue;
    local_triangle[static_cast<std::size_t>(t)] = static_cast<int>(kept.size());
    kept.push_back(static_cast<int>(t));
  }
  mesh->triangles.resize(3, static_cast<Index>(kept.size()));
  for (std::size_t t = 0; t < kept.size(); ++t)
    for (int a = 0; a < 3; ++a)
      mesh->triangles(a, static_cast<Index>(t)) =
          local_of[static_cast<std::size_t>(whole.triangles(a, kept[t]))];
  for (const MeshGroup& group : whole.groups) {
    MeshGroup g{group.name, group.dim, {}};
    const std::vector<int>& map = group.dim == 0   ? local_of
                                  : group.dim == 2 ? local_triangle
                                                   : local_tet;
    for (int item : group.items)
      if (map[static_cast<std::size_t>(item)] >= 0)
        g.items.push_back(map[static_cast<std::size_t>(item)]);
    std::sort(g.items.begin(), g.items.end());
    mesh->groups.push_back(std::move(g));
  }
  out.mesh = std::move(mesh);
  return out;
}

std::vector<double> GatherNodeValues(const MeshPart& part, const double* local, MPI_Comm comm) {
  const int owned = static_cast<int>(part.num_owned);
  std::vector<int> counts(static_cast<std::size_t>(part.size)),
      offsets(static_cast<std::size_t>(part.size), 0);
  MPI_Gather(&owned, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  std::partial_sum(counts.begin(), counts.end() - 1, offsets.begin() + 1);
  const int total = part.rank == 0 ? offsets.back() + counts.back() : 0;
  std::vector<int> ids(static_cast<std::size_t>(total));
  std::vector<double> values(static_cast<std::size_t>(total));
  MPI_Gatherv(part.whole_node.data(), owned, MPI_INT, ids.data(), counts.data(), offsets.data(),
              MPI_INT, 0, comm);
  MPI_Gatherv(local, owned, MPI_DOUBLE, values.data(), counts.data(), offsets.data(), MPI_DOUBLE, 0,
              comm);
  std::vector<double> out;
  if (part.rank != 0) return out;
  out.assign(static_cast<std::size_t>(part.num_global_nodes), 0.0);
  for (std::size_t i = 0; i < ids.size(); ++i) out[static_cast<std::size_t>(ids[i])] = values[i];
  return out;
}

}  // namespace gipsi
