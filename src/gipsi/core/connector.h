#pragma once
/// @file
/// `Connector`: couples simulation objects, either through a shared boundary (boundary values of
/// one → boundary conditions of the other) or through a shared volume (Get a field of one → Set a
/// field of the other). Connectors convert semantics and map between different meshes.

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/state_binding.h"
#include "gipsi/core/object_path.h"
#include "gipsi/core/port.h"
#include "gipsi/core/step_status.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class SimObject;

/// Base class of connectors. Not copyable or movable.
///
/// A connector resolves everything it needs (objects, field ids, mappings, buffers) when it is
/// built, throwing InputError for bad wiring, and declares its ports there (gipsi/core/port.h):
/// every field it reads or writes, with the units it works in, every object whose boundary
/// conditions it sets, every capability it calls, and what it needs of the order. The
/// coordinator checks them before the first step. `Fire` then only transfers values: it never
/// throws and allocates nothing.
class Connector {
 public:
  Connector(const Connector&) = delete;
  Connector& operator=(const Connector&) = delete;
  virtual ~Connector();

  /// The connector's own name: its key in "connectors".
  [[nodiscard]] const std::string& name() const { return name_; }
  /// The name messages give: "heart.cavity_coupling" for a connector of the aggregate "heart"
  /// (as SimObject::path); name() at the scene's top level.
  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] virtual std::string_view type_name() const = 0;

  /// Transfers values at simulated time `t`.
  StepStatus Fire(double t) {
    ++fire_count_;
    return DoFire(t);
  }
  [[nodiscard]] std::int64_t fire_count() const { return fire_count_; }
  /// What the last failed Fire adds to its status (e.g. an exception's message from a connector
  /// written in Python), quoted in the run's diagnostic; empty by default.
  [[nodiscard]] virtual std::string failure_detail() const { return {}; }
  /// Whether it couples the objects' parts process by process (objects split alike in a
  /// distributed run; gipsi/core/partitioned_object.h). Only such a connector may use a node or
  /// element field of an object made in blocks, of which each process holds only its part;
  /// Coordinator::Prepare refuses any other. False by default.
  [[nodiscard]] virtual bool couples_parts() const { return false; }
  /// What it uses of the objects it couples, and its constraints on the order, as declared by
  /// its constructor (checked by Coordinator::Prepare, listed by `gipsi validate`).
  [[nodiscard]] std::span<const PortUse> ports() const { return ports_; }
  [[nodiscard]] std::span<const OrderRule> order_rules() const { return order_rules_; }
  /// Checkpoints (gipsi/base/state.h): the fire count, then the type's own state
  /// (SaveConnectorState). RestoreState throws InputError for state from another scene.
  void SaveState(StateWriter& out) const;
  void RestoreState(StateReader& in);
  /// State that outlives a Fire (e.g. a low-pass filtered value), for a connector that bound
  /// none with BindState. The defaults write and read the bound state, and throw
  /// InputError("connector type X does not support checkpoints") when none is bound.
  virtual void SaveConnectorState(StateWriter& out) const;
  virtual void RestoreConnectorState(StateReader& in);
  /// Snapshots (gipsi/base/object_state.h), as SimObject's: a new box with the current state,
  /// copying into it, and restoring from it.
  [[nodiscard]] std::unique_ptr<ObjectState> NewSnapshot() const;
  void TakeSnapshot(ObjectState& into) const;
  void RestoreSnapshot(const ObjectState& from);
  /// Whether snapshots copy the state as a value (BindState, BindNoState) rather than
  /// serialising it through SaveConnectorState.
  [[nodiscard]] bool state_is_value() const { return state_binding_ != nullptr; }

 protected:
  explicit Connector(std::string name) : name_(std::move(name)), path_(ScopedObjectPath(name_)) {}
  virtual StepStatus DoFire(double t) = 0;
  /// Port declarations; call from the constructor. `key` is the connector's parameter naming
  /// that end ("from", "wall"). A field is read and/or written (`access`) in `units` (a
  /// UDUNITS-2 expression the field's units must convert to with factor 1; empty for any) with
  /// `components` (0 for any).
  void UseField(std::string key, const SimObject& object, std::string field, FieldAccess access,
                std::string units = {}, int components = 0);
  /// The connector sets boundary conditions (coupling loads or prescribed values) of `object`.
  void UseBoundaryConditions(std::string key, const SimObject& object);
  /// The connector calls `object` through the capability interface called `capability`.
  void UseCapability(std::string key, const SimObject& object, std::string capability);
  void RequireOrder(OrderRule rule) { order_rules_.push_back(std::move(rule)); }
  /// Declares the connector's state value type (gipsi/base/state_value.h), as
  /// SimObject::BindState: checkpoints write it and snapshots copy it with no hook of the
  /// connector's own. Call once, from the constructor.
  template <class S>
  void BindState(S& state) {
    BindStateBinding(BindStateValue(state));
  }
  /// A state value type `S` whose live values are kept in several members, as
  /// SimObject::BindGatheredState.
  template <class S, class Get, class Set>
  void BindGatheredState(Get get, Set set) {
    BindStateBinding(BindGatheredStateValue<S>(std::move(get), std::move(set)));
  }
  /// Declares that the connector keeps nothing from one Fire to the next (it only moves
  /// values): its checkpoints are empty and its snapshots copy nothing. Call from the
  /// constructor, instead of BindState.
  void BindNoState();
  /// Called after the bound state was replaced (a checkpoint or a snapshot restored). Default:
  /// nothing.
  virtual void StateRestored() {}
  /// Hooks of the snapshots, as SimObject's; the defaults copy the bound state, else serialise
  /// through SaveConnectorState / RestoreConnectorState into a ByteState.
  [[nodiscard]] virtual std::unique_ptr<ObjectState> NewConnectorState() const;
  virtual void CopyConnectorState(ObjectState& into) const;
  virtual void SetConnectorState(const ObjectState& from);

 private:
  void BindStateBinding(std::unique_ptr<StateBinding> binding);

  std::string name_;
  std::string path_;  // name_ under the ObjectPathScope active at construction
  std::unique_ptr<StateBinding> state_binding_;
  std::int64_t fire_count_ = 0;
  std::vector<PortUse> ports_;
  std::vector<OrderRule> order_rules_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
