#pragma once
/// @file
/// `AggregateObject`: an object made of objects and the connectors between them (the paper's
/// Heart = bioelectricity + muscle + blood). Its step runs its own coordination: parts sub-step
/// at their own rates inside the aggregate's step, connectors fire in the given order. Its fields
/// are its parts' fields under dotted names ("muscle.position").

#include <memory>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/base/export.h"
#include "gipsi/base/state_binding.h"
#include "gipsi/core/coordinator.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable or movable.
class AggregateObject : public SimObject {
 public:
  /// Takes a prepared coordinator (parts, connectors, order; `Prepare(dt)` called with this
  /// aggregate's dt) and exposes its parts' fields.
  AggregateObject(std::string name, Coordinator parts);

  [[nodiscard]] std::string_view type_name() const override { return "Aggregate"; }
  [[nodiscard]] const Points& domain_positions() const override { return empty_; }
  void CollectLeaves(std::vector<const SimObject*>& out) const override;
  [[nodiscard]] SimObject* FindPart(std::string_view name) const override;
  void BeginMacroStep() override { parts_.BeginMacroStep(); }
  [[nodiscard]] const Coordinator& parts() const { return parts_; }
  [[nodiscard]] std::string failure_detail() const override { return failure_detail_; }
  /// Wall time per part and per connector, then each part's own breakdown ("part: entry").
  [[nodiscard]] std::vector<ProfileEntry> ProfileBreakdown() const override;
  /// The parts, the connectors, then the state bound by BindAggregateState.
  void SaveObjectState(StateWriter& out) const override;
  /// Whether every part and connector keeps its state as a value (see SimObject).
  [[nodiscard]] bool state_is_value() const override;
  void RestoreObjectState(StateReader& in) override;

 protected:
  /// State of the subclass itself (e.g. a monitor's record), kept after the parts': a subclass
  /// with one binds its state value type (gipsi/base/state_value.h) once, from its constructor,
  /// and checkpoints and snapshots then copy it with no hook of its own (as
  /// SimObject::BindState). Without it the aggregate has no state of its own.
  template <class S>
  void BindAggregateState(S& state) {
    GIPSI_CHECK(!own_state_bound_, "aggregate '{}': BindAggregateState called twice", name());
    own_state_ = BindStateValue(state);
    own_state_bound_ = true;
  }
  /// Snapshots: the parts' snapshots (Coordinator::TakeSnapshot) and the subclass's own state.
  [[nodiscard]] std::unique_ptr<ObjectState> NewObjectState() const override;
  void CopyObjectState(ObjectState& into) const override;
  void SetObjectState(const ObjectState& from) override;
  /// Number of fields that forward to parts (ids 0 … n−1); a subclass declares its own after.
  [[nodiscard]] std::size_t num_part_fields() const { return proxies_.size(); }
  StepStatus DoStep(double t, double dt) override;
  void DoSetStopToken(StopToken token) override { parts_.SetStopToken(token); }
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;

 private:
  struct Proxy {
    SimObject* part;
    FieldId field;
  };
  Coordinator parts_;
  std::vector<Proxy> proxies_;  // indexed by this object's FieldId
  Points empty_ = Points(3, 0);
  std::string failure_detail_;               // set only when a part fails
  std::unique_ptr<StateBinding> own_state_;  // BindAggregateState's, or an empty NoState
  bool own_state_bound_ = false;
};

/// Builds the parts, connectors and order of an aggregate from `p` ({"dt", "parts",
/// "connectors", "order"}) and prepares them with its dt; throws InputError naming the path.
/// In an aggregate made in blocks (ctx.in_blocks), the parts InBlocksObjects allows among them
/// are made in blocks too (gipsi/core/in_blocks.h).
Coordinator BuildAggregateParts(const ObjectBuildContext& ctx, const JsonNode& p);

/// Registers "Aggregate": {"type": "Aggregate", "dt": macro step, "parts": {name: object...},
/// "connectors": {name: connector...}, "order": [names...]}.
void RegisterAggregate(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
