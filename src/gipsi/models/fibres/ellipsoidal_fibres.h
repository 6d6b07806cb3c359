#pragma once
/// @file
/// Fibres of a truncated ellipsoidal ventricle defined on its ellipsoidal coordinates, as the
/// cardiac-mechanics benchmark defines them (Land et al., "Verification of cardiac mechanics
/// software: benchmark problems and solutions for testing active and passive material
/// behaviour", Proc. R. Soc. A 471:20150641, 2015, problem 3). The wall is the family of
/// ellipsoids of revolution about the z axis through `centre`,
///   x = r_s(t) sin u cos v,  y = r_s(t) sin u sin v,  z = r_l(t) cos u,
/// r_s and r_l varying linearly in the transmural coordinate t from the endocardium's (t = 0) to
/// the epicardium's (t = 1), u in [−π, 0) (the apex at u = −π, below the centre), v the angle
/// about the axis. At a point the fibre is f = sin α ∂x/∂u/|∂x/∂u| + cos α ∂x/∂v/|∂x/∂v|: along
/// the meridian at α = ±90°, around the axis at α = 0, the helix angle α varying linearly in t
/// (+90° to −90° in the benchmark). Unlike the Laplace rule (rule_based_fibres.h) it needs no
/// solve, depends on the mesh only through the points it is asked at (so any quadrature point,
/// on any rank), and is smooth however coarse the mesh.

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The rule's inputs (lengths in m, angles in degrees). Plain struct with the benchmark's
/// angles.
struct EllipsoidalFibreRule {
  Vec3 centre = Vec3::Zero();
  double endo_short = 0, endo_long = 0;  ///< r_s and r_l at t = 0
  double epi_short = 0, epi_long = 0;    ///< r_s and r_l at t = 1
  double endo_angle = 90;                ///< helix angle at t = 0 [degrees]
  double epi_angle = -90;                ///< at t = 1
};

/// The point's transmural coordinate t (the ellipsoid of the family through it; points a little
/// outside the wall, e.g. on the facets of a straight-sided mesh, get t a little outside [0, 1]
/// and the angle there is clamped to the end's) and its fibre. Points on the axis take v = 0.
struct EllipsoidalFibre {
  double t = 0;
  Vec3 fibre = Vec3::UnitX();
};
[[nodiscard]] EllipsoidalFibre EllipsoidalFibreAt(const EllipsoidalFibreRule& rule,
                                                  const Vec3& point);

/// The rule's fibre at the centroid of every tet of `mesh` (3 by tets).
[[nodiscard]] Points EllipsoidalFibresAtCentroids(const Mesh& mesh,
                                                  const EllipsoidalFibreRule& rule);

/// Reads {"rule": "ellipsoidal", "endo": [r_short, r_long], "epi": [r_short, r_long],
/// "centre": [x, y, z], "endo_angle": degrees, "epi_angle": degrees} (radii in the scene's
/// length unit, already SI here); throws InputError naming the JSON path of a bad value.
[[nodiscard]] EllipsoidalFibreRule ParseEllipsoidalFibreRule(const JsonNode& node);

}  // namespace gipsi
GIPSI_EXPORT_END
