#pragma once
/// @file
/// Scene-file parsing shared by the solid objects' factories ("FemSolid", "MixedSolid").

#include <optional>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/models/fem/solid_material.h"
#include "gipsi/models/fibres/ellipsoidal_fibres.h"
#include "gipsi/models/fibres/rule_based_fibres.h"
#include "gipsi/numerics/implicit_scheme.h"
#include "gipsi/numerics/newton.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The "newton" object of a solid (keys in docs/scene-format.md) over `defaults`; throws
/// InputError naming the JSON path of a bad value.
[[nodiscard]] NewtonOptions ParseNewtonOptions(const JsonNode& node, NewtonOptions defaults);

/// The object's "load_steps" (an integer in [1, 100000]) and "max_bisections" (in [0, 30]),
/// each left as given when absent; throws InputError naming the JSON path of a bad value.
void ParseLoadStepping(const JsonNode& object, int& load_steps, int& max_bisections);

/// A solid's fibre rule, if its fibres come from one: the Laplace rule ("transmural") or the
/// benchmark ventricle's ("ellipsoidal"). Plain struct.
struct SolidFibreRule {
  std::optional<TransmuralFibreRule> transmural;
  std::optional<EllipsoidalFibreRule> ellipsoidal;
  explicit operator bool() const { return transmural || ellipsoidal; }
};

/// The object's "fibres": a rule (returned; its fibres are made on the mesh later), or a uniform
/// "direction" and "sheet" (into `fibre` and `sheet`). Without it, a law that needs fibres is
/// refused at "material". Throws InputError naming the JSON path of a bad value.
[[nodiscard]] SolidFibreRule ParseSolidFibres(const JsonNode& object, const SolidMaterial& law,
                                              Vec3& fibre, Vec3& sheet);
/// The object's "predictor" ("none", "constant_velocity" or "constant_acceleration"); `fallback`
/// when absent. Throws InputError naming the JSON path of a bad value.
[[nodiscard]] StepPredictor ParsePredictor(const JsonNode& object, StepPredictor fallback);

}  // namespace gipsi
GIPSI_EXPORT_END
