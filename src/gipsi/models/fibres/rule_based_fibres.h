#pragma once
/// @file
/// Rule-based myocardial fibres for a ventricle-like wall (after the Laplace–Dirichlet approach
/// of Bayer, Blake, Plank & Trayanova, Ann. Biomed. Eng. 40:2243, 2012, reduced to one
/// transmural coordinate and a long axis):
///  1. the transmural coordinate e solves Laplace's equation in the wall with e = 0 on the
///     endocardium and e = 1 on the epicardium (P1 tets, natural conditions elsewhere);
///  2. per element, t = ∇e/|∇e| (transmural, outward), c = k × t/|k × t| (circumferential, k the
///     long axis pointing from apex to base) and l = t × c (longitudinal, towards the base);
///  3. the fibre is f = cos α c + sin α l with the helix angle α varying linearly through the
///     wall, α = α_endo + (α_epi − α_endo) e (e at the element centroid); the sheet is t.
/// Where k ∥ t (at the apex) c is taken perpendicular to t along the first coordinate axis that
/// is not parallel to it.

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/geometry/mesh.h"
#include "gipsi/geometry/region.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The rule's inputs. Plain struct with defaults (±60°, a common choice for the human LV).
struct TransmuralFibreRule {
  Region endo;                ///< nodes where e = 0
  Region epi;                 ///< nodes where e = 1
  Vec3 axis = Vec3::UnitZ();  ///< long axis, apex → base
  double endo_angle = 60;     ///< helix angle at the endocardium [degrees]
  double epi_angle = -60;     ///< at the epicardium [degrees]
};

/// The result. Plain struct.
struct FibreField {
  VecX transmural;  ///< e per node, in [0, 1]
  Points fibre;     ///< 3 by E unit fibre directions
  Points sheet;     ///< 3 by E unit transmural directions
};

/// Applies the rule to the tets of `mesh`. Throws InputError if the mesh has no tets, if endo
/// or epi selects no node or they share a node, or if the Laplace solve fails.
FibreField MakeTransmuralFibres(const Mesh& mesh, const TransmuralFibreRule& rule);

/// Steps 2 and 3 above for the tets of `mesh`, given e at its nodes (`transmural`, one value per
/// node, moved into the result): how MakeTransmuralFibres ends, and how a solver that found e
/// otherwise (over the ranks, for one rank's part of a split mesh) gets the same fibres from it.
FibreField TransmuralFibresFrom(const Mesh& mesh, const TransmuralFibreRule& rule, VecX transmural);

/// The rule's fibre at transmural coordinate `e` in a tet whose unit transmural direction is
/// `t` (FibreField::sheet): f = cos α c + sin α l, α = α_endo + (α_epi − α_endo) e (step 3
/// above). MakeTransmuralFibres evaluates it at each tet's centroid; a solver may evaluate it
/// at its quadrature points (e interpolated from FibreField::transmural), so that a wall only
/// one or two tets thick still sees the fibre turn through it.
[[nodiscard]] Vec3 TransmuralFibreAt(const TransmuralFibreRule& rule, const Vec3& t, double e);

/// Reads the helix angles "endo_angle" and "epi_angle" of a fibre rule's `node` (degrees within
/// ±90) into `endo` and `epi`, each left as given when absent; throws InputError naming the JSON
/// path of a bad value.
void ParseHelixAngles(const JsonNode& node, double& endo, double& epi);

/// Reads {"rule": "transmural", "endo": region, "epi": region, "axis": [x, y, z],
/// "endo_angle": degrees, "epi_angle": degrees}; throws InputError naming the JSON path.
TransmuralFibreRule ParseTransmuralFibreRule(const JsonNode& node);

}  // namespace gipsi
GIPSI_EXPORT_END
