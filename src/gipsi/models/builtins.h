#pragma once
/// @file
/// Registration of every type GiPSi ships.

#include "gipsi/core/registry.h"

namespace gipsi {

/// Registers the built-in objects ("MassSpring", "FemSolid", "Aggregate"), connectors
/// ("FieldCopy", "BoundaryCoupling"), integrators ("ExplicitEuler", "SymplecticEuler", "RK4"),
/// spring laws ("Hooke", "Exponential") and solid laws ("Linear", "Corotational",
/// "StVenantKirchhoff", "NeoHookean", "Guccione") and cardiac cell models ("AlievPanfilov",
/// "MitchellSchaeffer", "FitzHughNagumo", "Nagumo", "TenTusscherPanfilov2006").
void RegisterBuiltins(TypeRegistry& registry);

}  // namespace gipsi
