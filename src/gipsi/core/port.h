#pragma once
/// @file
/// Ports: what a connector declares it uses of the objects it couples, and what it needs of the
/// schedule. An object's ports are its fields (`FieldInfo`: name, location, components, units,
/// read/write), its boundary conditions, and the capability interfaces it implements
/// (`CavityWall`, `LumpedChambers`). A connector lists, in its constructor, each end it uses
/// (`Connector::UseField`, `UseBoundaryConditions`, `UseCapability`) and each constraint on the
/// order (`Connector::RequireOrder`). `Coordinator::Prepare` checks all of them before the first
/// step, so a wrongly wired scene is refused with a message naming both ends instead of failing
/// at run time; `gipsi validate` prints them as the scene's wiring.

#include <stdexcept>
#include <string>

#include "gipsi/base/error.h"
#include "gipsi/base/export.h"
#include "gipsi/core/field.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class SimObject;

/// One end of a connector. Plain struct.
struct PortUse {
  enum class Kind {
    kField,               ///< a named field, read or written
    kBoundaryConditions,  ///< the object's boundary conditions (coupling loads, prescriptions)
    kCapability,          ///< a capability interface (the connector calls it)
  };
  Kind kind = Kind::kField;
  /// The connector's key naming this end ("from", "wall", "objects[1]"), for messages.
  std::string key;
  const SimObject* object = nullptr;
  /// The field's name, or the capability's ("cavity wall"); empty for boundary conditions.
  std::string name;
  /// Fields: what the connector does with it (kRead or kWrite; kReadWrite for both).
  FieldAccess access = FieldAccess::kRead;
  /// Fields: the units the connector works in (a UDUNITS-2 expression); the field must be
  /// declared in units that convert to them with factor 1. Empty: any units.
  std::string units;
  /// Fields: the components the connector expects (1, 3 or 9); 0 for any.
  int components = 0;
};

/// A constraint of a connector on the schedule: `first` steps before the connector fires and
/// `then` steps after it, within the same macro step. Plain struct.
struct OrderRule {
  const SimObject* first = nullptr;  ///< nullptr: no constraint before
  const SimObject* then = nullptr;   ///< nullptr: no constraint after
  /// `first` and `then` step with the same time step (the connector hands over a per-step
  /// quantity), and the connector fires every macro step.
  bool same_step = false;
  /// Why, in a few words ("the blood integrates with the pressure the wall solved").
  std::string reason;
};

/// Thrown by `Coordinator::Prepare` for a wiring the ports refuse. `connector` names the
/// connector; `order_path` is the JSON path of the order when the order is at fault and was
/// given explicitly (empty otherwise), so a scene loader can point at the right key.
class WiringError : public InputError {
 public:
  WiringError(const std::string& message, std::string connector, std::string order_path)
      : InputError(message), connector_(std::move(connector)), order_path_(std::move(order_path)) {}
  [[nodiscard]] const std::string& connector() const { return connector_; }
  [[nodiscard]] const std::string& order_path() const { return order_path_; }

 private:
  std::string connector_;
  std::string order_path_;
};

/// "reads", "writes" or "reads and writes" (what a connector does with a field).
std::string_view PortAccessName(FieldAccess access);

/// One line for `gipsi validate`: "reads wall.lumen_volume [m^3] (wall)",
/// "sets the boundary conditions of liver (objects[0])", "calls blood as lumped chambers
/// (blood)".
std::string DescribePort(const PortUse& port);
/// "after wall, before blood, same time step (REASON)".
std::string DescribeOrderRule(const OrderRule& rule);

}  // namespace gipsi
GIPSI_EXPORT_END
