#pragma once
/// @file
/// Reader for Gmsh `.msh` files: format 1.0 (`$NOD`/`$ELM`), 2.x ASCII and binary, and 4.1
/// ASCII and binary.

#include <cstdint>
#include <filesystem>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Reads a Gmsh mesh file.
///
/// Kept elements: 4-node tetrahedra (type 4) and 3-node triangles (type 2); second-order
/// tetrahedra (type 11) and triangles (type 9) become linear elements on their corners, and
/// their edges' middle nodes go to the mesh's second-order geometry (`Mesh::edge_nodes`, which
/// quadratic elements use for curved edges), not to its nodes. Other element types (points,
/// lines, quads, hexahedra, ...) are not kept, but their physical groups are.
///
/// Node tags may be any distinct positive integers: nodes are renumbered 0..N-1 in file order and
/// all nodes are kept (also those no kept element uses), except the middle nodes of
/// second-order edges.
///
/// Physical groups become `MeshGroup`s: a group of volumes holds tet indices (dim 3), a group of
/// surfaces triangle indices (dim 2), a group of curves or points node indices (dim 0). Names come
/// from `$PhysicalNames`; an unnamed group with tag t is called `physical_<t>`. If two groups of
/// different dimensions share a name, the later one gets the suffix `_dim<d>`. In format 4.1
/// elements inherit the physical tags of their entity (`$Entities`); in 1.0/2.x the first
/// element tag is the physical tag (0: none).
///
/// Throws InputError naming the file and the line (or byte offset for binary data) for a missing
/// file, an unsupported version, truncated sections, malformed numbers, non-finite coordinates,
/// elements with the wrong number of nodes, references to undefined nodes, duplicate node
/// tags, and second-order elements that disagree on an edge's middle node. The result has
/// passed `Mesh::Validate`.
Mesh ReadGmsh(const std::filesystem::path& path);

/// The same, also giving the file's element tag of every tet, in the order of the mesh's tets
/// (`(*tet_tags)[e]` is tet e's tag): messages can then name a tet as Gmsh does (tags are the
/// file's own, usually counting from 1), not by its 0-based index in the mesh.
Mesh ReadGmsh(const std::filesystem::path& path, std::vector<std::int64_t>* tet_tags);

}  // namespace gipsi
GIPSI_EXPORT_END
