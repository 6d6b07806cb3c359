#pragma once
/// @file
/// Scene-file parsing shared by the solid objects' factories ("FemSolid", "MixedSolid").

#include "gipsi/base/json_node.h"
#include "gipsi/numerics/newton.h"

namespace gipsi {

/// The "newton" object of a solid (keys in docs/scene-format.md) over `defaults`; throws
/// InputError naming the JSON path of a bad value.
[[nodiscard]] NewtonOptions ParseNewtonOptions(const JsonNode& node, NewtonOptions defaults);

}  // namespace gipsi
