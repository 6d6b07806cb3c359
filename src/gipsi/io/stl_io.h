#pragma once
/// @file
/// STL triangle surfaces (ASCII and binary): reader with vertex welding, and writer.

#include <filesystem>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Options of `ReadStl`.
struct StlReadOptions {
  /// STL stores every triangle with its own 3 corners; corners closer than this tolerance,
  /// relative to the diagonal of the bounding box, are welded into one vertex (0: only exactly
  /// equal corners are welded). Must be >= 0.
  double weld_tolerance = 1e-9;
};

/// Reads an STL file, ASCII or binary. The file is binary when its size is 84 + 50 n, n being
/// the triangle count stored at byte 80 (unless it is plain ASCII text containing `endsolid`);
/// otherwise it must be ASCII (`solid ... facet normal ... outer loop vertex ... endloop
/// endfacet ... endsolid`, several solids allowed; facets with more than 3 vertices are split
/// into fans). Stored normals are ignored.
///
/// Corners are welded with a hash grid (expected linear time; the first corner seen in a cluster
/// is its representative, vertices are numbered in order of first appearance) into a connected
/// triangle surface; triangles that become degenerate by welding are dropped.
///
/// Throws InputError naming the file and the line (ASCII) or byte offset (binary) for a missing
/// file, a size that is neither valid binary nor ASCII STL, truncated data, malformed keywords,
/// and malformed or non-finite numbers. The result has passed `Mesh::Validate`.
Mesh ReadStl(const std::filesystem::path& path, const StlReadOptions& options = {});

/// STL flavour written by `WriteStl`.
enum class StlFormat { kBinary, kAscii };

/// Writes `triangles` (3 by T, indices into `nodes`, 3 by N; checked) as STL with per-facet unit
/// normals (zero for degenerate triangles). Binary STL stores float32 coordinates (little-endian);
/// ASCII STL writes shortest round-trip decimals (exact). Throws InputError if the file cannot be
/// written.
void WriteStl(const std::filesystem::path& path, const Points& nodes, const Triangles& triangles,
              StlFormat format = StlFormat::kBinary);

}  // namespace gipsi
GIPSI_EXPORT_END
