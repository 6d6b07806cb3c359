#include "gipsi/core/coordinator.h"

#include <chrono>

#include <algorithm>
#include <cmath>
#include <set>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/json_node.h"

namespace gipsi {
namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

SimObject& Coordinator::AddObject(std::unique_ptr<SimObject> object, double dt) {
  GIPSI_CHECK(object != nullptr);
  if (!(dt > 0) || !std::isfinite(dt))
    throw InputError(
        fmt::format("object '{}': time step must be positive, got {}", object->path(), dt));
  for (const auto& slot : objects_)
    if (slot.object->name() == object->name())
      throw InputError(fmt::format("duplicate object name '{}'", object->path()));
  const auto* paced = dynamic_cast<const WallClockPaced*>(object.get());
  objects_.push_back({std::move(object), dt, 1, 0.0, paced});
  return *objects_.back().object;
}

Connector& Coordinator::AddConnector(std::unique_ptr<Connector> connector, int every) {
  GIPSI_CHECK(connector != nullptr);
  if (every < 1)
    throw InputError(
        fmt::format("connector '{}': 'every' must be >= 1, got {}", connector->path(), every));
  for (const auto& slot : connectors_)
    if (slot.connector->name() == connector->name())
      throw InputError(fmt::format("duplicate connector name '{}'", connector->path()));
  connectors_.push_back({std::move(connector), every});
  return *connectors_.back().connector;
}

void Coordinator::SetOrder(const std::vector<std::string>& names, std::string_view where) {
  std::vector<Entry> order;
  std::set<std::string> seen;
  std::vector<std::string> known = ObjectNames();
  for (const auto& c : connectors_) known.push_back(c.connector->name());
  for (const auto& name : names) {
    if (!seen.insert(name).second)
      throw InputError(fmt::format("{}: '{}' appears twice", where, name));
    bool found = false;
    for (std::size_t i = 0; i < objects_.size() && !found; ++i)
      if (objects_[i].object->name() == name) {
        order.push_back({false, i});
        found = true;
      }
    for (std::size_t i = 0; i < connectors_.size() && !found; ++i)
      if (connectors_[i].connector->name() == name) {
        order.push_back({true, i});
        found = true;
      }
    if (!found)
      throw InputError(fmt::format("{}: no object or connector named '{}'{}", where, name,
                                   SuggestClosest(name, known)));
  }
  for (const auto& name : known)
    if (!seen.count(name))
      throw InputError(
          fmt::format("{}: '{}' is missing; the order must name every object and "
                      "connector exactly once",
                      where, name));
  order_ = std::move(order);
  has_order_ = true;
  order_where_ = where;
}

double Coordinator::max_object_dt() const {
  double dt = 0;
  for (const auto& slot : objects_) dt = std::max(dt, slot.dt);
  return dt;
}

void Coordinator::Prepare(double macro_dt) {
  if (!(macro_dt > 0) || !std::isfinite(macro_dt))
    throw InputError(fmt::format("macro time step must be positive, got {}", macro_dt));
  for (auto& slot : objects_) {
    double ratio = macro_dt / slot.dt;
    double n = std::round(ratio);
    if (n < 1 || std::abs(ratio - n) > 1e-9 * ratio)
      throw InputError(fmt::format(
          "object '{}': its time step {} s does not divide the macro step {} s; choose a dt "
          "that divides it (multi-rate objects sub-step an integer number of times)",
          slot.object->path(), slot.dt, macro_dt));
    slot.substeps = static_cast<int>(n);
  }
  macro_dt_ = macro_dt;
  if (!has_order_) {
    order_.clear();
    for (std::size_t i = 0; i < connectors_.size(); ++i) order_.push_back({true, i});
    for (std::size_t i = 0; i < objects_.size(); ++i) order_.push_back({false, i});
  }
  CheckWiring();
}

void Coordinator::BeginMacroStep() {
  for (auto& slot : objects_) slot.object->BeginMacroStep();
}

void Coordinator::SetStopToken(StopToken token) {
  stop_ = token;
  for (auto& slot : objects_) slot.object->SetStopToken(token);
}

std::optional<ScheduleFailure> Coordinator::MacroStep(double t, std::int64_t macro_index,
                                                      int split) {
  GIPSI_CHECK(macro_dt_ > 0, "Coordinator::Prepare was not called");
  GIPSI_CHECK(split >= 1);
  const double macro_dt = split == 1 ? macro_dt_ : macro_dt_ / split;
  for (const Entry& entry : order_) {
    if (entry.is_connector) {
      ConnectorSlot& slot = connectors_[entry.index];
      if (macro_index % slot.every != 0) continue;
      const auto start = Clock::now();
      StepStatus status = slot.connector->Fire(t);
      slot.seconds += std::chrono::duration<double>(Clock::now() - start).count();
      if (!status.ok())
        return ScheduleFailure{status, slot.connector->name(), true, t,
                               slot.connector->failure_detail()};
    } else {
      ObjectSlot& slot = objects_[entry.index];
      const double dt = macro_dt / slot.substeps;
      const auto start = Clock::now();
      for (int k = 0; k < slot.substeps; ++k) {
        if (slot.paced != nullptr)
          WaitForWallClock(*slot.paced, slot.object->time(), slot.object->time() + dt, stop_);
        StepStatus status = slot.object->Step(dt);
        if (!status.ok()) {
          slot.seconds += std::chrono::duration<double>(Clock::now() - start).count();
          return ScheduleFailure{status, slot.object->name(), false, t + k * dt,
                                 slot.object->failure_detail()};
        }
      }
      slot.seconds += std::chrono::duration<double>(Clock::now() - start).count();
      slot.object->SetTime(t + macro_dt);
    }
  }
  return std::nullopt;
}

SimObject* Coordinator::FindObject(std::string_view name) const {
  std::string_view head = name.substr(0, name.find('.'));
  for (const auto& slot : objects_) {
    if (slot.object->name() == name) return slot.object.get();
    if (slot.object->name() == head && head.size() < name.size()) {
      return slot.object->FindPart(name.substr(head.size() + 1));
    }
  }
  return nullptr;
}

std::vector<std::string> Coordinator::ObjectNames() const {
  std::vector<std::string> names;
  for (const auto& slot : objects_) names.push_back(slot.object->name());
  return names;
}

}  // namespace gipsi
