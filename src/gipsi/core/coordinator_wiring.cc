/// @file
/// The coordinator's wiring check: every connector's declared ports against the objects'
/// fields, and its order rules against the schedule (gipsi/core/port.h).

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/base/error.h"
#include "gipsi/base/units.h"
#include "gipsi/core/aggregate.h"
#include "gipsi/core/coordinator.h"
#include "gipsi/core/partitioned_object.h"

namespace gipsi {
namespace {

bool Contains(const SimObject& top, const SimObject* object) {
  if (&top == object) return true;
  if (const auto* aggregate = dynamic_cast<const AggregateObject*>(&top))
    for (std::size_t i = 0; i < aggregate->parts().num_objects(); ++i)
      if (Contains(aggregate->parts().object(i), object)) return true;
  return false;
}

std::string Describe(const SimObject& object) {
  return fmt::format("'{}' ({})", object.path(), object.type_name());
}

// The field end of a port: its declaration must allow what the connector does, in the units
// and components it works with.
void CheckFieldPort(const Connector& c, const PortUse& port) {
  const SimObject& object = *port.object;
  const std::string who = fmt::format("connector '{}' ({})", c.path(), c.type_name());
  const std::string end =
      fmt::format("field '{}' of {} at its '{}' key", port.name, Describe(object), port.key);
  auto fail = [&](const std::string& what) {
    throw WiringError(fmt::format("{} {} {}, but {}", who, PortAccessName(port.access), end, what),
                      c.name(), "");
  };
  const std::optional<FieldId> id = object.TryFindField(port.name);
  if (!id) {
    std::vector<std::string> names;
    for (const FieldInfo& f : object.fields()) names.push_back(f.name);
    fail(fmt::format("that object has no such field (its fields: {})", fmt::join(names, ", ")));
  }
  const FieldInfo& info = object.field_info(*id);
  const bool reads = port.access != FieldAccess::kWrite;
  const bool writes = port.access != FieldAccess::kRead;
  if (reads && !info.readable()) fail("the field cannot be read (it is write-only)");
  if (writes && !info.writable()) fail("the field cannot be written (it is read-only)");
  if (port.components != 0 && info.components != port.components)
    fail(fmt::format("the field has {} component(s) and the connector works with {}",
                     info.components, port.components));
  if (port.units.empty() || info.units == port.units) return;
  double factor = 0;
  try {
    factor = UnitFactor(info.units, port.units);
  } catch (const std::invalid_argument&) {
    fail(fmt::format("the field is in [{}], which does not convert to the connector's [{}]",
                     info.units, port.units));
  }
  if (std::abs(factor - 1) > 1e-12)
    fail(fmt::format(
        "the field is in [{}] and the connector works in [{}] without converting (1 {} = {:g} "
        "{}); declare the field in the connector's units",
        info.units, port.units, info.units, factor, port.units));
}

// An end on an object made in blocks (each process holds only its part): its node and element
// fields and its boundary are the part's, so only a connector coupling parts may use them. Its
// global fields and capabilities are the whole object's.
void CheckPartOnlyPort(const Connector& c, const PortUse& port) {
  const auto* split = dynamic_cast<const PartitionedObject*>(port.object);
  if (split == nullptr || split->holds_whole_domain() || c.couples_parts()) return;
  if (port.kind == PortUse::Kind::kCapability) return;
  std::string end;
  if (port.kind == PortUse::Kind::kField) {
    const std::optional<FieldId> id = port.object->TryFindField(port.name);
    if (!id || port.object->field_info(*id).location == FieldLocation::kGlobal) return;
    end = fmt::format("{} field '{}' of {}", PortAccessName(port.access), port.name,
                      Describe(*port.object));
  } else {
    end = fmt::format("sets the boundary conditions of {}", Describe(*port.object));
  }
  throw WiringError(
      fmt::format("connector '{}' ({}) {} at its '{}' key, but that object is made in blocks in "
                  "this distributed run (each process holds only its part) and the connector "
                  "does not couple it part to part (ExcitationContraction, BoundaryCoupling "
                  "and FieldCopy do: docs/scale-out.md, \"Meshes in blocks\")",
                  c.path(), c.type_name(), end, port.key),
      c.name(), "");
}

}  // namespace

int Coordinator::TopLevelIndex(const SimObject* object) const {
  for (std::size_t i = 0; i < objects_.size(); ++i)
    if (Contains(*objects_[i].object, object)) return static_cast<int>(i);
  return -1;
}

std::string Coordinator::OrderText() const {
  std::vector<std::string> names;
  for (const Entry& e : order_)
    names.push_back(e.is_connector ? connectors_[e.index].connector->name()
                                   : objects_[e.index].object->name());
  return fmt::format("[{}]", fmt::join(names, ", "));
}

void Coordinator::CheckWiring() const {
  std::vector<int> object_position(objects_.size(), -1);
  std::vector<int> connector_position(connectors_.size(), -1);
  for (std::size_t k = 0; k < order_.size(); ++k)
    (order_[k].is_connector ? connector_position : object_position)[order_[k].index] =
        static_cast<int>(k);

  for (std::size_t ci = 0; ci < connectors_.size(); ++ci) {
    const Connector& c = *connectors_[ci].connector;
    const std::string who = fmt::format("connector '{}' ({})", c.path(), c.type_name());
    for (const PortUse& port : c.ports()) {
      GIPSI_CHECK(port.object != nullptr, "a port of connector '{}' names no object", c.path());
      if (TopLevelIndex(port.object) < 0)
        throw WiringError(fmt::format("{} uses object '{}' at its '{}' key, which is not among "
                                      "the objects it is scheduled with",
                                      who, port.object->path(), port.key),
                          c.name(), "");
      if (port.kind == PortUse::Kind::kField) CheckFieldPort(c, port);
      CheckPartOnlyPort(c, port);
    }

    for (const OrderRule& rule : c.order_rules()) {
      const int first = rule.first ? TopLevelIndex(rule.first) : -1;
      const int then = rule.then ? TopLevelIndex(rule.then) : -1;
      GIPSI_CHECK((rule.first == nullptr || first >= 0) && (rule.then == nullptr || then >= 0),
                  "an order rule of connector '{}' names an object it is not scheduled with",
                  c.path());
      const int here = connector_position[ci];
      const bool first_ok = first < 0 || object_position[static_cast<std::size_t>(first)] < here;
      const bool then_ok = then < 0 || object_position[static_cast<std::size_t>(then)] > here;
      std::string wanted;
      if (rule.first && rule.then)
        wanted = fmt::format("after '{}' steps and before '{}' steps", rule.first->name(),
                             rule.then->name());
      else if (rule.first)
        wanted = fmt::format("after '{}' steps", rule.first->name());
      else if (rule.then)
        wanted = fmt::format("before '{}' steps", rule.then->name());
      const std::string order =
          has_order_ ? fmt::format("the order {}", OrderText())
                     : fmt::format("the default order (every connector, then every object: {})",
                                   OrderText());
      if (!first_ok || !then_ok)
        throw WiringError(fmt::format("{} must fire {} ({}), but {} does not; list them in "
                                      "that order",
                                      who, wanted, rule.reason, order),
                          c.name(), has_order_ ? order_where_ : "");
      if (!rule.same_step) continue;
      if (connectors_[ci].every != 1)
        throw WiringError(fmt::format("{} must fire every macro step ({}), but 'every' is {}", who,
                                      rule.reason, connectors_[ci].every),
                          c.name(), "");
      if (first >= 0 && then >= 0 &&
          objects_[static_cast<std::size_t>(first)].dt !=
              objects_[static_cast<std::size_t>(then)].dt)
        throw WiringError(
            fmt::format("{} needs '{}' and '{}' to step with the same time step ({}), but "
                        "they step with {} s and {} s",
                        who, rule.first->name(), rule.then->name(), rule.reason,
                        objects_[static_cast<std::size_t>(first)].dt,
                        objects_[static_cast<std::size_t>(then)].dt),
            c.name(), "");
    }
  }
}

}  // namespace gipsi
