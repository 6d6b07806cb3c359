#pragma once
/// @file
/// Triangle surfaces of tool primitives.

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A closed, outward-oriented triangle surface of a capsule: the points within `radius` of the
/// segment from the origin to (0, 0, length) (a sphere when length is 0). `segments` (>= 3)
/// divisions around the axis; each hemisphere has segments / 2 rings (at least 2). Throws
/// InputError for a non-positive radius, a negative length or segments < 3.
Mesh MakeCapsuleSurface(double radius, double length, int segments);

}  // namespace gipsi
GIPSI_EXPORT_END
