#pragma once
/// @file
/// What every cavity wall (FemSolid, MassSpring) shares of its cavities, written once: the scene
/// entry ("cavities": {"NAME": REGION}), the faces and nodes a region selects, the enclosed
/// volume over them (rim capped), the "<name>_volume" and "<name>_pressure" fields, the blood law
/// a CavityCoupling attaches, and the lookups behind CavityWall's `cavity_names` and
/// `AttachCavityLaw`. Each model adds what its own solve needs (FemSolid: ∂V/∂x over the whole
/// mesh; MassSpring: the step's gradient and the law's compliance).

#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/core/cavity_law.h"
#include "gipsi/core/field.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/enclosed_volume.h"
#include "gipsi/geometry/mesh.h"
#include "gipsi/geometry/region.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A cavity bounded by part of the boundary (an endocardium). Plain struct.
struct CavitySpec {
  std::string name;  ///< fields "<name>_volume" [m³] and "<name>_pressure" [Pa]
  Region region;     ///< selects the boundary faces that bound the cavity
};

/// The scene's "cavities" object: {"NAME": REGION, …}, in order. Errors name the JSON path.
std::vector<CavitySpec> ParseCavitySpecs(const JsonNode& node);

/// One cavity of a wall. Movable.
struct WallCavity {
  std::vector<int> faces;         ///< boundary faces bounding it
  std::vector<int> nodes;         ///< domain node of each cavity vertex
  EnclosedVolume volume;          ///< over the faces, oriented out of the cavity
  mutable Points positions;       ///< work buffer, 3 by nodes.size()
  mutable Points local_gradient;  ///< work buffer, 3 by nodes.size()
  FieldId f_volume, f_pressure;
  CavityLaw* law = nullptr;  ///< coupled to blood when set (by AttachCavityLaw)

  /// The enclosed volume [m³] with the cavity's nodes at columns `nodes` of `x` (3 by N), and
  /// ∂V/∂x of each cavity vertex in `local_gradient` when `gradient` is true.
  double Volume(const Points& x, bool gradient = false) const;
};

/// Builds the cavities of `specs` on `mesh` and its boundary, declaring each one's two fields
/// through `declare` (the object's DeclareField; `pressure_description` describes how its
/// pressure acts). Throws InputError naming `object` and the cavity for a region that selects
/// no face or a surface whose rim is not a set of simple loops.
std::vector<WallCavity> MakeWallCavities(std::string_view object, std::span<const CavitySpec> specs,
                                         const Mesh& mesh, const BoundarySurface& boundary,
                                         const std::function<FieldId(FieldInfo)>& declare,
                                         std::string_view pressure_description);

/// One cavity of MakeWallCavities, on faces already selected (`faces` of `boundary`, in the
/// order the cavity keeps them). The same checks and fields.
WallCavity MakeWallCavity(std::string_view object, const CavitySpec& spec,
                          const BoundarySurface& boundary, std::vector<int> faces,
                          const std::function<FieldId(FieldInfo)>& declare,
                          std::string_view pressure_description);

/// −dp/dV_b of `law` at pressure p [Pa/m³] over the step [t, t + dt], given V_b(p) = vb: a
/// one-sided difference of 1e-6 of the pressure (at least 1 mPa); 0 if the law fails there or
/// is not decreasing (then p is not determined by the volume). The weight of a cavity's
/// rank-one tangent term and 1 / ∂r_p/∂p of its bordered pressure.
double CavityLawStiffness(CavityLaw& law, double t, double dt, double p, double vb);

/// The names of `specs`, in order (CavityWall::cavity_names).
std::vector<std::string> CavityNames(std::span<const CavitySpec> specs);

/// The index of cavity `cavity` among `specs`. Throws InputError "object 'NAME' (TYPE) has no
/// cavity 'C'; its cavities: …".
std::size_t FindCavity(std::string_view object, std::string_view type,
                       std::span<const CavitySpec> specs, std::string_view cavity);
/// Throws InputError "object 'NAME': cavity 'C' is already coupled to blood".
[[noreturn]] void ThrowCavityAlreadyCoupled(std::string_view object, std::string_view cavity);

/// The index of cavity `cavity` for AttachCavityLaw: FindCavity, and its `law` (an element of
/// `cavities`, WallCavity or derived, parallel to `specs`) must not be set yet.
template <class Cavities>
std::size_t FindUncoupledCavity(std::string_view object, std::string_view type,
                                std::span<const CavitySpec> specs, const Cavities& cavities,
                                std::string_view cavity) {
  const std::size_t i = FindCavity(object, type, specs, cavity);
  if (cavities[i].law != nullptr) ThrowCavityAlreadyCoupled(object, cavity);
  return i;
}

}  // namespace gipsi
GIPSI_EXPORT_END
