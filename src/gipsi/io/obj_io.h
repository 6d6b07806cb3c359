#pragma once
/// @file
/// Wavefront OBJ triangle surfaces: reader and writer.

#include <filesystem>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Reads the vertices (`v x y z [w]`) and faces (`f ...`) of an OBJ file; everything else
/// (`vt`, `vn`, `g`, `o`, `s`, `usemtl`, `mtllib`, comments) is ignored. Face corners may be
/// written `i`, `i/t`, `i//n` or `i/t/n`; negative indices count back from the last vertex
/// defined so far. Polygons with more than 3 corners are split into a fan from their first
/// corner. Returns a triangle-only mesh.
///
/// Throws InputError naming the file and line for a missing file, malformed or non-finite
/// numbers, faces with fewer than 3 corners or a repeated corner, index 0 and out-of-range
/// indices. The result has passed `Mesh::Validate`.
Mesh ReadObj(const std::filesystem::path& path);

/// Writes `nodes` (3 by N) as `v` lines, with shortest round-trip decimal formatting (reading
/// back gives identical doubles), and `triangles` (3 by T, indices in [0, N), checked) as 1-based
/// `f` lines. Throws InputError if the file cannot be written.
void WriteObj(const std::filesystem::path& path, const Points& nodes, const Triangles& triangles);

}  // namespace gipsi
GIPSI_EXPORT_END
