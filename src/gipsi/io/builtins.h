#pragma once
/// @file
/// Registration of every type GiPSi ships: the catalogue the scene loader builds objects from.
/// It lives in io, the first layer above models, collision and haptics, since it registers the
/// types of all three (each of those layers registers only its own, e.g. `RegisterFemSolid`).

#include "gipsi/base/export.h"
#include "gipsi/core/registry.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Registers the built-in objects ("MassSpring", "FemSolid", "Aggregate"), connectors
/// ("FieldCopy", "BoundaryCoupling"), integrators ("ExplicitEuler", "SymplecticEuler", "RK4"),
/// spring laws ("Hooke", "Exponential") and solid laws ("Linear", "Corotational",
/// "StVenantKirchhoff", "NeoHookean", "Guccione") and cardiac cell models ("AlievPanfilov",
/// "MitchellSchaeffer", "FitzHughNagumo", "Nagumo", "TenTusscherPanfilov2006").
void RegisterBuiltins(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
