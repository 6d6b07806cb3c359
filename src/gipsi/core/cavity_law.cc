#include "gipsi/core/cavity_law.h"

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/core/sim_object.h"

namespace gipsi {

CavityWall& CavityWallOf(SimObject& object) {
  auto* wall = dynamic_cast<CavityWall*>(&object);
  if (wall == nullptr)
    throw InputError(fmt::format(
        "object '{}' ({}) has no cavities to couple to blood; a wall with cavities is a "
        "FemSolid or MassSpring with \"cavities\" (or a plugin type implementing CavityWall)",
        object.name(), object.type_name()));
  return *wall;
}

LumpedChambers& LumpedChambersOf(SimObject& object) {
  auto* chambers = dynamic_cast<LumpedChambers*>(&object);
  if (chambers == nullptr)
    throw InputError(fmt::format(
        "object '{}' ({}) has no lumped chambers to take a cavity's pressure; the blood side "
        "of a cavity coupling is a Circulation (or a plugin type implementing LumpedChambers)",
        object.name(), object.type_name()));
  return *chambers;
}

}  // namespace gipsi
