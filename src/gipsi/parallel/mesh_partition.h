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
/// The cut is made from blocks (PartitionMeshBlocks): each rank gives one contiguous block of
/// the mesh's nodes, tets and triangles (geometry/mesh_block.h), the dual graph is built from
/// them by exchanges between the ranks, and the parts are assembled from what the ranks send;
/// no rank holds the whole mesh, so a reader or generator that makes only its block needs
/// O(mesh / ranks) memory per rank. PartitionMesh cuts a mesh every rank already holds (the
/// scene loader reads it whole on every rank) through the same path, into the same parts.

#include <mpi.h>

#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/mesh.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/geometry/region.h"

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

/// Splits `whole` (identical on every rank of `comm`) over the ranks (see the file comment):
/// PartitionMeshBlocks of its blocks (BlockOfMesh). Collective. On one rank the part is the whole
/// mesh in its own order. Throws InputError if the mesh has fewer tets than there are ranks, and
/// std::runtime_error if PT-Scotch fails.
MeshPart PartitionMesh(const Mesh& whole, MPI_Comm comm);

/// Splits a mesh given as one block per rank (geometry/mesh_block.h), which no rank holds whole,
/// over the ranks of `comm` (see the file comment): the same parts as PartitionMesh of the
/// whole mesh. Collective; each rank holds O(its block + its part). Throws InputError if the
/// mesh has fewer tets than there are ranks, more than 2^31 - 1 items of a kind, or a tet or
/// triangle naming a node it does not have, and std::runtime_error if PT-Scotch fails.
MeshPart PartitionMeshBlocks(const MeshBlock& block, MPI_Comm comm);

/// The whole-mesh indices of the nodes any rank selected (`local`: this rank's selection, local
/// node indices), sorted and unique, the same on every rank. A region selected on each rank's
/// part may miss a node that the part holds: a triangle or tet group names the node only where
/// the group's triangle or tet is, which may be another rank's. Collective; O(selected).
std::vector<int> GatherSelectedNodes(const MeshPart& part, std::span<const int> local,
                                     MPI_Comm comm);
/// Every rank's `mine`, in rank order, the same on every rank. Collective; O(all of them).
std::vector<int> GatherAll(std::span<const int> mine, MPI_Comm comm);
/// Every rank's `mine`, sorted and unique, the same on every rank. Collective; O(the union).
std::vector<int> GatherUnion(std::span<const int> mine, MPI_Comm comm);
/// The local indices, ascending, of the whole-mesh nodes `whole` that this part holds.
std::vector<int> LocalNodesOf(const MeshPart& part, std::span<const int> whole);

/// The whole mesh's bounding box (its lowest and highest corners) from the parts'. Collective.
std::pair<Vec3, Vec3> WholeBoundingBox(const MeshPart& part, MPI_Comm comm);
/// The whole mesh's RegionTolerance (geometry/region.h) from the parts' bounding boxes: the
/// tolerance at which a part selects by position what the whole mesh would. Collective.
double WholeRegionTolerance(const MeshPart& part, MPI_Comm comm);
/// The local nodes (ascending) of `part` that `region` selects on the whole mesh, found without
/// it: a position is decided where the node is, at `tolerance` (WholeRegionTolerance); node ids
/// are whole-mesh indices (one out of range throws InputError); a group's nodes are gathered
/// from every rank (GatherSelectedNodes). Collective (every rank must call it with the same
/// region); O(the part), and O(the selection) for a group.
std::vector<int> SelectPartNodes(const Region& region, const MeshPart& part, double tolerance,
                                 MPI_Comm comm);

/// The whole mesh's boundary on this rank's part, found without the whole mesh: the whole
/// boundary's faces of local tets (outward, in the order of their tets), and every local node on
/// the whole boundary as a vertex (in local order), also one that only another part's faces
/// touch. The same surface as the whole mesh's boundary (MakeBoundary) restricted to the part.
/// Collective; O(part) per rank.
BoundarySurface PartBoundary(const MeshPart& part, MPI_Comm comm);

/// The vertices of `boundary` (ascending) whose node is in `nodes` (ascending).
std::vector<int> BoundaryVerticesOfNodes(const BoundarySurface& boundary,
                                         std::span<const int> nodes);
/// The faces of a part's boundary (`boundary`, PartBoundary's or the whole boundary's faces of
/// the part) that `region` selects as SelectBoundaryFaces does on the whole mesh: a triangle
/// group's faces matched to the part's triangles, any other region's faces whose three vertices
/// it selects (SelectPartNodes at `tolerance`). Collective; O(the part's boundary).
std::vector<int> SelectPartBoundaryFaces(const Region& region, const MeshPart& part,
                                         const BoundarySurface& boundary, double tolerance,
                                         MPI_Comm comm);

/// Where a part's boundary (PartBoundary's) lies on the whole mesh's (MakeBoundary's), found
/// without the whole mesh. Plain struct.
struct WholeBoundaryNumbers {
  std::vector<int> vertex;  ///< the whole boundary's vertex of each part boundary vertex
  std::vector<int> face;    ///< the whole boundary's face of each part face
  std::int64_t whole_vertices = 0, whole_faces = 0;  ///< the whole boundary's counts
};
/// The whole boundary orders its vertices by node and its faces by tet, then by the tet's local
/// node the face is opposite to (MakeBoundary): each item's number is its rank among every
/// part's items in that order, counted at the block rank of its node or tet (one exchange
/// there and back). Collective; O(the part's boundary) per rank.
WholeBoundaryNumbers NumberOnWholeBoundary(const MeshPart& part, const BoundarySurface& boundary,
                                           MPI_Comm comm);

/// What MoveRows delivered. Plain struct.
struct MovedRows {
  std::vector<double> rows;   ///< a row per held item, in the order of `held`
  std::int64_t missing = 0;   ///< held items no row reached, summed over the ranks
  std::int64_t repeated = 0;  ///< rows given again for an item (every rank's count)
  std::int64_t outside = 0;   ///< rows given for no item in [0, count) (every rank's count)
  int first_missing = -1;     ///< the lowest missing item (-1: none)
};
/// Sends rows of `width` values, each given by some rank for an item (`whole[j]` in
/// [0, `count`) for row j of `rows`: a whole mesh's node, tet or boundary face), to every rank
/// that holds the item (`held`: this rank's items, e.g. a part's whole_node): how state moves
/// from one partition to another (a checkpoint restored on another rank count). Each row
/// passes through its item's block rank (BlockBegin), which learns who holds the item; so
/// every rank sends and keeps O(its rows + its items), and an item given by no rank, or by two,
/// is counted (the caller decides; the counts are the same on every rank). Collective.
MovedRows MoveRows(std::span<const int> held, std::int64_t count, std::span<const int> whole,
                   std::span<const double> rows, int width, MPI_Comm comm);

/// Every rank's owned values of a node field, gathered on rank 0 in the whole mesh's node order
/// (`local`: one value per local node of `part`). Collective; ranks other than 0 get an empty
/// vector.
std::vector<double> GatherNodeValues(const MeshPart& part, const double* local, MPI_Comm comm);

}  // namespace gipsi
GIPSI_EXPORT_END
