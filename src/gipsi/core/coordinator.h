#pragma once
/// @file
/// `Coordinator`: the user-defined coordination of a set of objects and connectors: execution
/// order, a time step per object (multi-rate sub-stepping inside a macro step) and how often each
/// connector fires. Used by the `Kernel` for the whole scene and by `AggregateObject` for its
/// parts.

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/connector.h"
#include "gipsi/core/pacing.h"
#include "gipsi/core/sim_object.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Where a macro step stopped, if it did not complete. `who` names the object or connector
/// (points into its name; valid while the coordinator lives).
struct ScheduleFailure {
  StepStatus status;
  std::string_view who;
  bool is_connector = false;
  double time = 0;     ///< simulated time at the start of the failing sub-step
  std::string detail;  ///< the object's or connector's failure_detail()
};

/// Owns objects and connectors and runs them in order. Not copyable; movable.
///
/// Build phase: `AddObject`, `AddConnector`, optionally `SetOrder`, then `Prepare(macro_dt)`.
/// Run phase: `MacroStep` repeatedly. Default order (no SetOrder): every connector in insertion
/// order, then every object: a staggered exchange at the start of each macro step.
class Coordinator {
 public:
  Coordinator() = default;
  Coordinator(Coordinator&&) = default;
  Coordinator& operator=(Coordinator&&) = default;

  /// Adds an object stepped with time step `dt` (> 0). Throws InputError for a duplicate name.
  SimObject& AddObject(std::unique_ptr<SimObject> object, double dt);
  /// Adds a connector fired every `every` macro steps (>= 1).
  Connector& AddConnector(std::unique_ptr<Connector> connector, int every = 1);
  /// Sets the execution order: names of objects and connectors, each exactly once. Throws
  /// InputError for unknown, repeated or missing names (`where` is prefixed to messages).
  void SetOrder(const std::vector<std::string>& names, std::string_view where = "schedule.order");

  /// Fixes the macro step and each object's sub-step count, and checks the wiring. Every object
  /// dt must divide `macro_dt` to within 1e-9 relative; otherwise throws InputError naming the
  /// object. Every connector's ports (gipsi/core/port.h) must match the objects' fields (name,
  /// access, components, units) and the order must meet its order rules; otherwise throws
  /// WiringError naming the connector and both ends.
  void Prepare(double macro_dt);
  /// Largest object dt (the natural macro step), or 0 when there are no objects.
  [[nodiscard]] double max_object_dt() const;
  /// The macro step fixed by Prepare (0 before).
  [[nodiscard]] double macro_dt() const { return macro_dt_; }

  /// Runs one macro step from time t: for each entry in order, sub-steps an object
  /// `substeps` times or fires a due connector. Stops at the first failure. Never throws. An
  /// object that is WallClockPaced (gipsi/core/pacing.h) is never stepped past the wall clock:
  /// the coordinator waits before its sub-step until the wall clock reaches the sub-step's end.
  /// `split` > 1 makes it a 1/split fraction of a macro step (every object's sub-step divided
  /// by split; connectors fire as in the full step): the kernel's retry after a failure.
  std::optional<ScheduleFailure> MacroStep(double t, std::int64_t macro_index, int split = 1);
  /// Forwards `BeginMacroStep` to every object.
  void BeginMacroStep();
  /// Hands `token` to every object (SimObject::SetStopToken); a stop request also ends a wait
  /// for the wall clock.
  void SetStopToken(StopToken token);

  /// Snapshots of every object and connector (a CompositeState, gipsi/base/object_state.h):
  /// the kernel's step retry and an aggregate's state. Objects first, then connectors.
  [[nodiscard]] std::unique_ptr<ObjectState> NewSnapshot() const;
  void TakeSnapshot(ObjectState& into) const;
  void RestoreSnapshot(const ObjectState& from);
  [[nodiscard]] std::size_t num_objects() const { return objects_.size(); }
  [[nodiscard]] std::size_t num_connectors() const { return connectors_.size(); }
  [[nodiscard]] SimObject& object(std::size_t i) { return *objects_[i].object; }
  [[nodiscard]] const SimObject& object(std::size_t i) const { return *objects_[i].object; }
  [[nodiscard]] double object_dt(std::size_t i) const { return objects_[i].dt; }
  [[nodiscard]] int object_substeps(std::size_t i) const { return objects_[i].substeps; }
  [[nodiscard]] Connector& connector(std::size_t i) { return *connectors_[i].connector; }
  [[nodiscard]] const Connector& connector(std::size_t i) const {
    return *connectors_[i].connector;
  }
  /// Wall-clock seconds spent stepping object i / firing connector i so far.
  [[nodiscard]] double object_seconds(std::size_t i) const { return objects_[i].seconds; }
  [[nodiscard]] double connector_seconds(std::size_t i) const { return connectors_[i].seconds; }
  /// The object called `name` (dotted names reach into aggregates: "heart.muscle"), or nullptr.
  [[nodiscard]] SimObject* FindObject(std::string_view name) const;
  /// Names of every object (for messages).
  [[nodiscard]] std::vector<std::string> ObjectNames() const;

 private:
  struct ObjectSlot {
    std::unique_ptr<SimObject> object;
    double dt = 0;
    int substeps = 1;
    double seconds = 0;
    const WallClockPaced* paced = nullptr;  // the object, if it runs on the wall clock
  };
  struct ConnectorSlot {
    std::unique_ptr<Connector> connector;
    int every = 1;
    double seconds = 0;
  };
  struct Entry {
    bool is_connector = false;
    std::size_t index = 0;
  };
  std::vector<ObjectSlot> objects_;
  std::vector<ConnectorSlot> connectors_;
  /// Throws WiringError for a port or order rule the scene does not meet (coordinator_wiring.cc).
  void CheckWiring() const;
  /// The index of the top-level object that is or contains `object` (in an aggregate), or -1.
  [[nodiscard]] int TopLevelIndex(const SimObject* object) const;
  /// The order as names, "[a, b, c]", for messages.
  [[nodiscard]] std::string OrderText() const;

  std::vector<Entry> order_;
  bool has_order_ = false;
  std::string order_where_;
  double macro_dt_ = 0;
  StopToken stop_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
