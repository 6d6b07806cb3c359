#pragma once
/// @file
/// A human-readable summary of a mesh, for `gipsi info`.

#include <string>

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Counts (nodes, tets, triangles, boundary faces), named groups, bounding box, element quality
/// (inverted and degenerate tets with their ids, aspect ratios, volume) and, for surfaces,
/// whether they are closed and manifold.
/// Tets are named by the file's own ids (Mesh::tet_ids, e.g. Gmsh element tags) when the mesh has
/// them, else by their 0-based index; the kind of id is stated.
std::string DescribeMesh(const Mesh& mesh);

}  // namespace gipsi
GIPSI_EXPORT_END
