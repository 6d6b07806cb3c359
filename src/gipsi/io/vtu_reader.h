#pragma once
/// @file
/// Reader for VTK XML unstructured grids (`.vtu`).

#include <filesystem>

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Reads a VTK XML `UnstructuredGrid` file. Supported data arrays: `format="ascii"`,
/// `format="binary"` (inline base64) and `format="appended"` (raw or base64 `AppendedData`),
/// uncompressed or with `compressor="vtkZLibDataCompressor"`, `header_type` UInt32 or UInt64,
/// either byte order, element types Int8..UInt64, Float32 and Float64. All pieces are read and
/// concatenated. Cells of type 10 (tetrahedron) and 5 (triangle) are kept, and quadratic ones (24
/// and 22) as linear cells on their corners, their edges' middle points going to the mesh's
/// second-order geometry (`Mesh::edge_nodes`) as with Gmsh's; others are ignored.
/// Point and cell data are not read.
///
/// Declared sizes are checked against the data actually present before allocating. Throws
/// InputError naming the file, the line of the offending XML element and what was expected, for
/// a missing file, malformed XML, a wrong dataset type, an unsupported compressor or data type,
/// bad base64, truncated or inconsistent data, non-finite coordinates and out-of-range indices.
/// The result has passed `Mesh::Validate`.
Mesh ReadVtu(const std::filesystem::path& path);

}  // namespace gipsi
GIPSI_EXPORT_END
