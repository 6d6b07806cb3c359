#pragma once
/// @file
/// Element quality checks for tetrahedral meshes, reported with element ids.

#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Quality of a tet mesh. Aspect ratio is longest edge / (2·sqrt(6)·inradius): 1 for the
/// regular tetrahedron, growing without bound as an element flattens.
struct TetQualityReport {
  Index num_tets = 0;
  std::vector<int> inverted;    ///< tets with negative signed volume (node order 0-1-2-3)
  std::vector<int> degenerate;  ///< tets with |volume| <= tolerance·(longest edge)^3
  double min_volume = 0, max_volume = 0, total_volume = 0;  ///< signed volumes
  double min_aspect = 0, max_aspect = 0, mean_aspect = 0;   ///< over non-degenerate tets
  int worst_aspect_tet = -1;                                ///< id of the max-aspect tet
};

/// Signed volume of tet (a, b, c, d): ((b-a)×(c-a))·(d-a)/6, positive for right-handed order.
double TetSignedVolume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Checks every tet of (`nodes` 3 by N, `tets` 4 by E). `degenerate_tolerance` is relative to
/// the cube of the longest edge.
TetQualityReport CheckTetQuality(const Points& nodes, const Tets& tets,
                                 double degenerate_tolerance = 1e-10);

}  // namespace gipsi
GIPSI_EXPORT_END
