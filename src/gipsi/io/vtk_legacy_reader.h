#pragma once
/// @file
/// Reader for legacy VTK `.vtk` files (ASCII and BINARY).

#include <filesystem>

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh.h"

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

}  // namespace gipsi
GIPSI_EXPORT_END
