#pragma once
/// @file
/// Boundary conditions and loads from scene JSON, applied to an object's boundary geometry.
///
///   {"name": "clamp", "region": <region>, "fix": true | ["x", "z"]}
///   {"region": <region>, "displacement": [ux, uy, uz], "axes": ["x", "y", "z"]}
///   {"region": <region>, "velocity": [vx, vy, vz], "axes": [...]}
///   {"region": <region>, "force": [fx, fy, fz]}        N on every selected vertex
///   {"region": <region>, "total_force": [fx, fy, fz]}  N split equally over the vertices
///   {"region": <region>, "pressure": p}                Pa on the selected boundary triangles
///   {"region": <region>, "traction": [tx, ty, tz]}     Pa on the selected boundary triangles
/// `region` defaults to "all"; `name` (optional) lets scheduled events remove the condition.

#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/core/boundary_conditions.h"
#include "gipsi/core/sim_object.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// One condition resolved on one object's boundary. Copyable and movable.
struct BoundaryConditionSpec {
  enum class Kind { kFix, kDisplacement, kVelocity, kForce, kPressure, kTraction };
  std::string name;  ///< user name, or "#<index>" when unnamed
  std::string path;  ///< JSON path, for messages
  Kind kind = Kind::kFix;
  AxisMask axes = kAllAxes;
  Vec3 vector = Vec3::Zero();  ///< displacement, velocity, force (per vertex) or traction
  double scalar = 0;           ///< pressure
  /// Items of the object's store of conditions (a split object's: its part's boundary's).
  std::vector<int> vertices;  ///< boundary vertices (kinematic conditions and forces)
  std::vector<int> faces;     ///< boundary triangles (pressure, traction)

  /// Writes the condition into `bcs`.
  void Apply(BoundaryConditions& bcs) const;
  /// Undoes it: releases the constrained axes or zeroes the applied loads it set.
  void Remove(BoundaryConditions& bcs) const;
};

/// Parses one condition for `object` (selecting its region on the object's domain mesh and
/// boundary). Throws InputError naming the JSON path, also when the region selects nothing.
BoundaryConditionSpec ParseBoundaryCondition(const JsonNode& node, const SimObject& object,
                                             std::size_t index);

}  // namespace gipsi
GIPSI_EXPORT_END
