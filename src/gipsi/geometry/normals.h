#pragma once
/// @file
/// Areas and normals of triangle surfaces. `vertices` is 3 by V, `triangles` 3 by T.

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Area of each triangle (T entries).
VecX TriangleAreas(const Points& vertices, const Triangles& triangles);

/// Unit normal of each triangle (3 by T), right-hand rule; zero for a degenerate triangle.
Points FaceNormals(const Points& vertices, const Triangles& triangles);

/// Area-weighted unit vertex normals (3 by V), written into `normals` (resized if needed; no
/// allocation when it already is 3 by V). Vertices used by no triangle get a zero normal.
void VertexNormals(const Points& vertices, const Triangles& triangles, Points& normals);

}  // namespace gipsi
GIPSI_EXPORT_END
