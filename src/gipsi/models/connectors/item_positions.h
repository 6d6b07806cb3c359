#pragma once
/// @file
/// Reference positions of the items a field lives on, used to build mappings between objects.

#include "gipsi/base/export.h"
#include "gipsi/core/sim_object.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// 3 by count rest positions of the items of a field at `location` on `object`: domain nodes,
/// element centroids, boundary vertices or boundary face centroids. Global fields have none
/// (3 by 0).
Points ItemRestPositions(const SimObject& object, FieldLocation location);

}  // namespace gipsi
GIPSI_EXPORT_END
