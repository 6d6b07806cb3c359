#pragma once
/// @file
/// Reading one process's block of a Gmsh mesh (geometry/mesh_block.h) without holding the
/// whole mesh, for objects split over the processes of a distributed run: each process streams
/// the file through a small buffer and keeps only its block, so a mesh too large for one
/// process's memory is never read whole anywhere.

#include <filesystem>
#include <optional>

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh_block.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Block `rank` of `size` of the Gmsh mesh at `path`: the same block as
/// BlockOfMesh(ReadMesh(path), rank, size) (nodes, tets, triangles, groups, and the tets'
/// element tags), made in two streaming passes over the file (the first checks the whole file
/// and counts, the second keeps the block). Memory: the block, a 1 MiB read buffer and the
/// file's physical names and entities; plus 16 bytes per node of the whole mesh when its node
/// tags are not 1..N (or any run of consecutive tags) in file order.
///
/// Reads formats 1.0, 2.x (ASCII and binary) and 4.1 (ASCII and binary) with linear elements.
/// Returns nothing for a file it does not read in blocks (second-order elements, more than one
/// node or element section, a version ReadGmsh refuses): read such a file whole (ReadMesh), which
/// reads or refuses it, and slice it. Throws InputError naming the file and the line (or byte
/// offset in binary data) for the errors ReadGmsh reports.
std::optional<MeshBlock> ReadGmshBlock(const std::filesystem::path& path, int rank, int size);

}  // namespace gipsi
GIPSI_EXPORT_END
