#pragma once
/// @file
/// Regions from scene JSON. One key names the kind:
///   "all"                                   every node / face
///   {"box": {"min": [x,y,z], "max": [x,y,z]}}
///   {"half_space": {"point": [x,y,z], "normal": [x,y,z]}}
///   {"sphere": {"center": [x,y,z], "radius": r}}
///   {"group": "name"}                       a named group of the mesh (Gmsh physical group)
///   {"nodes": [i, j, ...]}                  explicit domain node ids

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/geometry/region.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Parses a region; throws InputError naming the JSON path for anything else.
Region ParseRegion(const JsonNode& node);

}  // namespace gipsi
GIPSI_EXPORT_END
