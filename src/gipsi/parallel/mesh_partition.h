#pragma once
/// @file
/// Splitting a tetrahedral mesh over the ranks of an MPI communicator. The tets are cut by
/// PT-Scotch (the partitioner Debian's PETSc comes with; ParMETIS's licence keeps it out of
/// Debian main) on the mesh's dual graph (tets joined across shared faces), balanced by tet
/// count, in Scotch's deterministic mode with a fixed seed: the same mesh on the same rank
/// count is cut the same way in every run (checkpoints of a distributed run rely on it). Each rank
/// keeps its tets and every node they use; a node used by several ranks is owned by the lowest of
/// them, and each rank's owned nodes take a contiguous block of the global (PETSc) numbering, in
/// the whole mesh's order.
///
/// Every rank reads the whole mesh first (the scene loader does), so the peak memory per rank
/// is the whole mesh plus its part: about 100 bytes per tet for the mesh and 60 for the
/// partitioning's graph (docs/scale-out.md). Reading a mesh in parallel is for later.

#include <mpi.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// One rank's part of a mesh. Plain struct.
struct MeshPart {
  /// This rank's tets and the nodes they use: local nodes [0, num_owned) are owned by this
  /// rank, the others are shared with (and owned by) lower ranks. Both keep the whole mesh's
  /// relative order. Node groups keep their local nodes, tet groups their local tets, and the
  /// triangles (and triangle groups) those that are a face of a local tet.
  std::shared_ptr<const Mesh> mesh;
  std::int64_t num_owned = 0;
  /// Global (PETSc) index of every local node; owned node i has first_owned + i.
  std::vector<std::int64_t> global;
  std::vector<int> whole_node;  ///< index in the whole mesh of every local node
  std::vector<int> whole_tet;   ///< index in the whole mesh of every local tet
  std::int64_t first_owned = 0;
  std::int64_t num_global_nodes = 0;
  std::int64_t num_global_tets = 0;
  int rank = 0;
  int size = 1;

  [[nodiscard]] std::int64_t num_local() const {
    return static_cast<std::int64_t>(whole_node.size());
  }
};

/// Splits `whole` (identical on every rank of `comm`) over the ranks (see the file comment).
/// Collective. On one rank the part is the whole mesh in its own order. Throws InputError if
/// the mesh has fewer tets than there are ranks, and std::runtime_error if PT-Scotch fails.
MeshPart PartitionMesh(const Mesh& whole, MPI_Comm comm);

/// Every rank's owned values of a node field, gathered on rank 0 in the whole mesh's node order
/// (`local`: one value per local node of `part`). Collective; ranks other than 0 get an empty
/// vector.
std::vector<double> GatherNodeValues(const MeshPart& part, const double* local, MPI_Comm comm);

}  // namespace gipsi
GIPSI_EXPORT_END
