#pragma once
/// @file
/// `Connector`: couples simulation objects, either through a shared boundary (boundary values of
/// one → boundary conditions of the other) or through a shared volume (Get a field of one → Set a
/// field of the other). Connectors convert semantics and map between different meshes.

#include <memory>
#include <string>
#include <string_view>

#include "gipsi/core/step_status.h"

namespace gipsi {

class ObjectState;
class StateReader;
class StateWriter;

/// Base class of connectors. Not copyable or movable.
///
/// A connector resolves everything it needs (objects, field ids, mappings, buffers) when it is
/// built, throwing InputError for bad wiring; `Fire` then only transfers values: it never
/// throws and allocates nothing.
class Connector {
 public:
  Connector(const Connector&) = delete;
  Connector& operator=(const Connector&) = delete;
  virtual ~Connector() = default;

  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] virtual std::string_view type_name() const = 0;

  /// Transfers values at simulated time `t`.
  StepStatus Fire(double t) {
    ++fire_count_;
    return DoFire(t);
  }
  [[nodiscard]] std::int64_t fire_count() const { return fire_count_; }
  /// Checkpoints (gipsi/base/state.h): the fire count, then the type's own state
  /// (SaveConnectorState). RestoreState throws InputError for state from another scene.
  void SaveState(StateWriter& out) const;
  void RestoreState(StateReader& in);
  /// State that outlives a Fire (e.g. a low-pass filtered value); connectors that only transfer
  /// values override these with empty bodies. The defaults throw InputError("connector type X
  /// does not support checkpoints").
  virtual void SaveConnectorState(StateWriter& out) const;
  virtual void RestoreConnectorState(StateReader& in);
  /// Snapshots (gipsi/base/object_state.h), as SimObject's: a new box with the current state,
  /// copying into it, and restoring from it.
  [[nodiscard]] std::unique_ptr<ObjectState> NewSnapshot() const;
  void TakeSnapshot(ObjectState& into) const;
  void RestoreSnapshot(const ObjectState& from);

 protected:
  explicit Connector(std::string name) : name_(std::move(name)) {}
  virtual StepStatus DoFire(double t) = 0;
  /// Hooks of the snapshots, as SimObject's; the defaults serialise through
  /// SaveConnectorState / RestoreConnectorState into a ByteState.
  [[nodiscard]] virtual std::unique_ptr<ObjectState> NewConnectorState() const;
  virtual void CopyConnectorState(ObjectState& into) const;
  virtual void SetConnectorState(const ObjectState& from);

 private:
  std::string name_;
  std::int64_t fire_count_ = 0;
};

}  // namespace gipsi
