/// @file
/// The PT-Scotch call of the partitioner, the whole-mesh entry point and the gather of a
/// node field (the cut itself: mesh_partition_blocks.cc).

#include "gipsi/parallel/mesh_partition.h"

#include <fmt/format.h>
#include <stdio.h>  // NOLINT(modernize-deprecated-headers): ptscotch.h needs FILE declared

#include <scotch/ptscotch.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>
#include <numeric>
#include <utility>
#include <variant>

#include "gipsi/base/error.h"
#include "gipsi/parallel/mesh_partition_detail.h"

namespace gipsi {
namespace {

constexpr SCOTCH_Num kScotchSeed = 20041;  // any fixed number
static_assert(sizeof(SCOTCH_Num) == sizeof(int), "the parts are gathered as MPI_INT");

// PT-Scotch's calls return 0 on success.
void Scotch(int code, const char* what) {
  if (code != 0)
    throw std::runtime_error(fmt::format("PT-Scotch failed in {} (error {})", what, code));
}

}  // namespace

namespace detail {

// Called directly rather than through PETSc's MatPartitioning, which cannot ask for Scotch's
// deterministic mode: Debian builds Scotch with threads, and its default mode cut the same mesh
// differently in every call.
std::vector<int> ScotchPart(const std::vector<int>& rows, std::vector<int>& columns, MPI_Comm comm,
                            int size) {
  const auto local = static_cast<SCOTCH_Num>(rows.size() - 1);
  std::vector<SCOTCH_Num> block(static_cast<std::size_t>(local) + 1, 0);
  if (size == 1) {
    block.pop_back();
    return block;
  }
  const SCOTCH_Num edges = rows.back();
  std::vector<SCOTCH_Num> offsets(rows.begin(), rows.end());
  SCOTCH_Dgraph graph, bound;
  SCOTCH_Context context;
  SCOTCH_Strat strategy;
  Scotch(SCOTCH_dgraphInit(&graph, comm), "SCOTCH_dgraphInit");
  Scotch(SCOTCH_contextInit(&context), "SCOTCH_contextInit");
  SCOTCH_stratInit(&strategy);
  int code = SCOTCH_dgraphBuild(&graph, 0, local, local, offsets.data(), nullptr, nullptr, nullptr,
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
  block.pop_back();
  return block;
}

}  // namespace detail

MeshPart PartitionMesh(const Mesh& whole, MPI_Comm comm) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  return PartitionMeshBlocks(BlockOfMesh(whole, rank, size), comm);
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

std::vector<int> GatherSelectedNodes(const MeshPart& part, std::span<const int> local,
                                     MPI_Comm comm) {
  std::vector<int> mine;
  mine.reserve(local.size());
  for (const int i : local) mine.push_back(part.whole_node[static_cast<std::size_t>(i)]);
  return GatherUnion(mine, comm);
}

std::vector<int> GatherAll(std::span<const int> mine, MPI_Comm comm) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  const int count = static_cast<int>(mine.size());
  std::vector<int> counts(static_cast<std::size_t>(size)),
      offsets(static_cast<std::size_t>(size), 0);
  MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  std::partial_sum(counts.begin(), counts.end() - 1, offsets.begin() + 1);
  std::vector<int> all(static_cast<std::size_t>(offsets.back() + counts.back()));
  MPI_Allgatherv(mine.data(), count, MPI_INT, all.data(), counts.data(), offsets.data(), MPI_INT,
                 comm);
  return all;
}

std::vector<int> GatherUnion(std::span<const int> mine, MPI_Comm comm) {
  std::vector<int> all = GatherAll(mine, comm);
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}

std::vector<int> LocalNodesOf(const MeshPart& part, std::span<const int> whole) {
  std::vector<std::pair<int, int>> by_whole;  // (whole index, local index)
  by_whole.reserve(part.whole_node.size());
  for (std::size_t i = 0; i < part.whole_node.size(); ++i)
    by_whole.emplace_back(part.whole_node[i], static_cast<int>(i));
  std::sort(by_whole.begin(), by_whole.end());
  std::vector<int> out;
  for (const int w : whole) {
    const auto it = std::lower_bound(by_whole.begin(), by_whole.end(), std::make_pair(w, -1));
    if (it != by_whole.end() && it->first == w) out.push_back(it->second);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::pair<Vec3, Vec3> WholeBoundingBox(const MeshPart& part, MPI_Comm comm) {
  const Points& x = part.mesh->nodes;
  Vec3 low = Vec3::Constant(std::numeric_limits<double>::infinity()), high = -low;
  if (x.cols() > 0) {
    low = x.rowwise().minCoeff();
    high = x.rowwise().maxCoeff();
  }
  MPI_Allreduce(MPI_IN_PLACE, low.data(), 3, MPI_DOUBLE, MPI_MIN, comm);
  MPI_Allreduce(MPI_IN_PLACE, high.data(), 3, MPI_DOUBLE, MPI_MAX, comm);
  return {low, high};
}

double WholeRegionTolerance(const MeshPart& part, MPI_Comm comm) {
  const auto [low, high] = WholeBoundingBox(part, comm);
  return RegionTolerance(low, high);
}

std::vector<int> SelectPartNodes(const Region& region, const MeshPart& part, double tolerance,
                                 MPI_Comm comm) {
  if (const auto* ids = std::get_if<NodeIdsRegion>(&region)) {
    for (std::size_t i = 0; i < ids->ids.size(); ++i)
      if (ids->ids[i] < 0 || ids->ids[i] >= part.num_global_nodes)
        throw InputError(fmt::format("node id {} (ids[{}]) out of range [0, {})", ids->ids[i], i,
                                     part.num_global_nodes));
    return LocalNodesOf(part, ids->ids);
  }
  std::vector<int> local = SelectNodes(region, *part.mesh, tolerance);
  // A triangle or tet group names a node only on the ranks that hold its triangle or tet.
  if (std::holds_alternative<GroupRegion>(region))
    local = LocalNodesOf(part, GatherSelectedNodes(part, local, comm));
  return local;
}

}  // namespace gipsi
