#pragma once
/// @file
/// Reader for legacy VTK `.vtk` files (ASCII and BINARY), whole or one process's block.

#include <filesystem>
#include <optional>

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh.h"
#include "gipsi/geometry/mesh_block.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Reads a legacy VTK file, ASCII or BINARY (big-endian), with `DATASET UNSTRUCTURED_GRID` or
/// `DATASET POLYDATA`.
///
/// Unstructured grids: cells of type 10 (tetrahedron) and 5 (triangle) are kept, other cell
/// types are ignored. Polydata: `POLYGONS` become triangles (polygons with more than 3 vertices
/// are split into a fan from their first vertex) and `TRIANGLE_STRIPS` are split into triangles;
/// triangles that repeat a vertex are dropped; `VERTICES` and `LINES` are ignored. Cell arrays
/// may use the classic `CELLS n size` layout or the VTK 5.1 `OFFSETS`/`CONNECTIVITY` layout.
/// `FIELD` and `METADATA` blocks are skipped; reading stops at `POINT_DATA`/`CELL_DATA`.
///
/// Every count declared in a header is checked against the rest of the file before anything is
/// allocated. Throws InputError naming the file and the line (and, for binary data, the byte
/// offset or section) for a missing file, an unsupported dataset or data type, truncated data,
/// malformed or non-finite numbers, inconsistent cell arrays and out-of-range point indices.
/// The result has passed `Mesh::Validate`.
Mesh ReadVtkLegacy(const std::filesystem::path& path);

/// Block `rank` of `size` of the legacy VTK unstructured grid at `path`: the same block as
/// BlockOfMesh(ReadVtkLegacy(path), rank, size) (points, tets, triangles; the format has no
/// groups), made in two streaming passes through a 1 MiB buffer, for an object split over the
/// processes of a distributed run. The first pass checks the file section by section and counts;
/// since CELL_TYPES follows CELLS, it keeps each cell's kind, 2 bits a cell of the whole grid;
/// the second pass checks every tet and triangle and keeps the block's. Memory: the block, the
/// kinds, and in the VTK 5.1 layout 8 bytes for each cell that is neither a tet nor a triangle.
///
/// Returns nothing for a file it does not read in blocks (`DATASET POLYDATA`, which holds no
/// tets; a second CELLS or CELL_TYPES section): read such a file whole. Throws InputError
/// naming the file and the line (or byte offset in binary data) for the errors ReadVtkLegacy
/// reports; where a file holds several, it may name another one first.
std::optional<MeshBlock> ReadVtkLegacyBlock(const std::filesystem::path& path, int rank, int size);

}  // namespace gipsi
GIPSI_EXPORT_END
