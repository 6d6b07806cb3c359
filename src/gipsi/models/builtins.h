#pragma once
/// @file
/// Registration of every type GiPSi ships.

#include "gipsi/core/registry.h"

namespace gipsi {

/// Registers the built-in objects ("MassSpring", "Aggregate"), connectors ("FieldCopy",
/// "BoundaryCoupling"), integrators ("ExplicitEuler", "SymplecticEuler", "RK4") and spring
/// laws ("Hooke", "Exponential").
void RegisterBuiltins(TypeRegistry& registry);

}  // namespace gipsi
