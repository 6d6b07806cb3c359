#pragma once
/// @file
/// Reader for TetGen `.node` / `.ele` / `.face` file triples.

#include <filesystem>

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh.h"
#include "gipsi/geometry/mesh_block.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Reads the TetGen mesh whose files share the stem of `path` (which may name the `.node`, the
/// `.ele` or the `.face` file): `STEM.node` and `STEM.ele` are required, `STEM.face` is read
/// when present. Comments (`#` to end of line) and blank lines are ignored.
///
/// Node numbers may start at 0 or 1 (as the first node says) or be any distinct integers: `.ele`
/// and `.face` refer to them by number and nodes are renumbered 0..N-1 in file order. 10-node
/// (second-order) tetrahedra contribute their 4 corners. The first region attribute of each tet
/// (`.ele`, when it declares attributes) yields tet groups `region_<a>`; the boundary marker of
/// each face (`.face`, when it declares markers) yields triangle groups `marker_<m>`.
///
/// Throws InputError naming the file and line for a missing `.node`/`.ele` file, bad headers,
/// short lines, malformed or non-finite numbers, duplicate node numbers and references to
/// undefined nodes. The result has passed `Mesh::Validate`.
///
/// Each file is streamed once through a buffer of about 1 MiB, so memory is the mesh and, when
/// the node numbers are not consecutive in file order, 16 bytes per node for the table from
/// number to node.
Mesh ReadTetGen(const std::filesystem::path& path);

/// Block `rank` of `size` of the same mesh (geometry/mesh_block.h), without the whole mesh:
/// the same block as BlockOfMesh(ReadTetGen(path), rank, size). Every line of the three files is
/// read and checked (so every process reports the errors ReadTetGen reports), and the block's
/// nodes, tets and faces are kept. Memory: the block, a 1 MiB read buffer, the distinct region
/// attributes and markers, and the node-number table above when one is needed.
MeshBlock ReadTetGenBlock(const std::filesystem::path& path, int rank, int size);

}  // namespace gipsi
GIPSI_EXPORT_END
