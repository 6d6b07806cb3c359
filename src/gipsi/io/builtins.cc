#include "gipsi/io/builtins.h"

#include "gipsi/collision/contact.h"
#include "gipsi/collision/rigid_tool.h"
#include "gipsi/core/aggregate.h"
#include "gipsi/haptics/haptic_probe.h"
#include "gipsi/models/circulation/circulation.h"
#include "gipsi/models/connectors/boundary_coupling.h"
#include "gipsi/models/connectors/cavity_coupling.h"
#include "gipsi/models/connectors/excitation_contraction.h"
#include "gipsi/models/connectors/field_copy.h"
#include "gipsi/models/ep/cell_models.h"
#include "gipsi/models/ep/grid_monodomain.h"
#include "gipsi/models/ep/monodomain.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/mixed_solid.h"
#include "gipsi/models/heart/heart.h"
#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {

void RegisterBuiltins(TypeRegistry& registry) {
  RegisterIntegrators(registry);
  RegisterSpringLaws(registry);
  RegisterMassSpring(registry);
  RegisterSolidLaws(registry);
  RegisterFemSolid(registry);
  RegisterMixedSolid(registry);
  RegisterCellModels(registry);
  RegisterMonodomain(registry);
  RegisterGridMonodomain(registry);
  RegisterCirculation(registry);
  RegisterAggregate(registry);
  RegisterHeart(registry);
  RegisterFieldCopy(registry);
  RegisterExcitationContraction(registry);
  RegisterCavityCoupling(registry);
  RegisterBoundaryCoupling(registry);
  RegisterRigidTool(registry);
  RegisterContact(registry);
  RegisterHaptics(registry);
}

}  // namespace gipsi
