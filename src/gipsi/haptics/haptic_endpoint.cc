#include "gipsi/haptics/haptic_endpoint.h"

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/core/sim_object.h"

namespace gipsi {

HapticEndpoint& HapticEndpointOf(SimObject& object) {
  auto* endpoint = dynamic_cast<HapticEndpoint*>(&object);
  if (endpoint == nullptr)
    throw InputError(fmt::format(
        "object '{}' ({}) is not a haptic device; a device is a HapticProbe (or a plugin type "
        "implementing HapticEndpoint)",
        object.name(), object.type_name()));
  return *endpoint;
}

}  // namespace gipsi
