#pragma once
/// @file
/// `MeshBlock`: one rank's contiguous slice of a mesh that no rank holds whole, the input of
/// the parallel partitioner (parallel/mesh_partition.h). Rank r of `size` holds the items
/// [count·r/size, count·(r+1)/size) of each kind (nodes, tets, triangles), their connectivity in
/// the whole mesh's node numbering. A parallel reader or a generator fills its own block; a
/// whole mesh can be sliced (BlockOfMesh) for the path that reads it on every rank.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The first item of rank `rank`'s block when `count` items are split over `size` ranks:
/// count·rank/size (so rank `size` gives `count`).
[[nodiscard]] inline std::int64_t BlockBegin(std::int64_t count, int rank, int size) {
  return count * rank / size;
}

/// One rank's block of a mesh (see the file comment). Plain data.
struct MeshBlock {
  std::int64_t num_nodes = 0;      ///< of the whole mesh
  std::int64_t num_tets = 0;       ///< of the whole mesh
  std::int64_t num_triangles = 0;  ///< of the whole mesh
  int rank = 0, size = 1;          ///< whose block this is, of how many
  Points nodes = Points(3, 0);     ///< the block's nodes [BlockBegin(num_nodes, rank, size), ...)
  Tets tets = Tets(4, 0);          ///< the block's tets, whole-mesh node indices
  Triangles triangles = Triangles(3, 0);  ///< the block's triangles, whole-mesh node indices
  std::int64_t first_triangle = 0;        ///< whole-mesh index of the block's first triangle
  /// The file's ids of the block's tets, and what they are (Mesh::tet_ids); empty when the
  /// mesh has none.
  std::vector<std::int64_t> tet_ids;
  std::string tet_id_kind;
  /// Every group of the whole mesh, in the same order on every rank, each listing the items
  /// (whole-mesh indices) that lie in this rank's block.
  std::vector<MeshGroup> groups;

  [[nodiscard]] std::int64_t node_begin() const { return BlockBegin(num_nodes, rank, size); }
  [[nodiscard]] std::int64_t tet_begin() const { return BlockBegin(num_tets, rank, size); }
};

/// Rank `rank`'s block of `whole`. Second-order geometry (Mesh::edge_nodes) is not carried:
/// the objects that are split run on linear tets, which see the corners either way.
MeshBlock BlockOfMesh(const Mesh& whole, int rank, int size);

/// Rank `rank`'s block of MakeTetBox(min, max, cells, split), made without the whole mesh:
/// the same nodes and tets (same numbering) and the same boundary triangles (each outward) and
/// groups, but the triangles numbered in the order of the tets they bound (MakeTetBox orders
/// them by box face): the block holds the triangles of its tets. Throws InputError as
/// MakeTetBox does.
MeshBlock MakeTetBoxBlock(const Vec3& min, const Vec3& max, const std::array<int, 3>& cells,
                          HexSplit split, int rank, int size);

}  // namespace gipsi
GIPSI_EXPORT_END
