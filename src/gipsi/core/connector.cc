/// @file
/// Connector port declarations (gipsi/core/port.h).

#include "gipsi/core/connector.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/base/error.h"
#include "gipsi/core/sim_object.h"

namespace gipsi {

std::string_view PortAccessName(FieldAccess access) {
  switch (access) {
    case FieldAccess::kRead:
      return "reads";
    case FieldAccess::kWrite:
      return "writes";
    case FieldAccess::kReadWrite:
      return "reads and writes";
  }
  return "uses";
}

std::string DescribePort(const PortUse& port) {
  const std::string& object = port.object->path();
  switch (port.kind) {
    case PortUse::Kind::kField:
      return fmt::format("{} {}.{}{} ({})", PortAccessName(port.access), object, port.name,
                         port.units.empty() ? "" : " [" + port.units + "]", port.key);
    case PortUse::Kind::kBoundaryConditions:
      return fmt::format("sets the boundary conditions of {} ({})", object, port.key);
    case PortUse::Kind::kCapability:
      return fmt::format("calls {} as {} ({})", object, port.name, port.key);
  }
  return {};
}

std::string DescribeOrderRule(const OrderRule& rule) {
  std::vector<std::string> parts;
  if (rule.first) parts.push_back("after " + rule.first->path() + " steps");
  if (rule.then) parts.push_back("before " + rule.then->path() + " steps");
  if (rule.same_step) parts.emplace_back("same time step, every macro step");
  return fmt::format("fires {} ({})", fmt::join(parts, ", "), rule.reason);
}

void Connector::UseField(std::string key, const SimObject& object, std::string field,
                         FieldAccess access, std::string units, int components) {
  GIPSI_CHECK(components == 0 || components == 1 || components == 3 || components == 9);
  ports_.push_back({PortUse::Kind::kField, std::move(key), &object, std::move(field), access,
                    std::move(units), components});
}

void Connector::UseBoundaryConditions(std::string key, const SimObject& object) {
  ports_.push_back({PortUse::Kind::kBoundaryConditions,
                    std::move(key),
                    &object,
                    {},
                    FieldAccess::kWrite,
                    {},
                    0});
}

void Connector::UseCapability(std::string key, const SimObject& object, std::string capability) {
  ports_.push_back({PortUse::Kind::kCapability,
                    std::move(key),
                    &object,
                    std::move(capability),
                    FieldAccess::kReadWrite,
                    {},
                    0});
}

}  // namespace gipsi
