/// @file
/// AggregateObject checkpoints and snapshots: every part, then every connector, in the
/// coordinator's order, then the subclass's own state (bound by BindAggregateState; none by
/// default).

#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/core/aggregate.h"

namespace gipsi {

void AggregateObject::SaveObjectState(StateWriter& out) const {
  out.WriteInt(static_cast<std::int64_t>(parts_.num_objects()));
  out.WriteInt(static_cast<std::int64_t>(parts_.num_connectors()));
  for (std::size_t i = 0; i < parts_.num_objects(); ++i) parts_.object(i).SaveState(out);
  for (std::size_t i = 0; i < parts_.num_connectors(); ++i) parts_.connector(i).SaveState(out);
  own_state_->Write(out);
}

void AggregateObject::RestoreObjectState(StateReader& in) {
  if (in.ReadInt() != static_cast<std::int64_t>(parts_.num_objects()) ||
      in.ReadInt() != static_cast<std::int64_t>(parts_.num_connectors()))
    in.Fail("the aggregate has a different number of parts or connectors in the checkpoint");
  for (std::size_t i = 0; i < parts_.num_objects(); ++i) parts_.object(i).RestoreState(in);
  for (std::size_t i = 0; i < parts_.num_connectors(); ++i) parts_.connector(i).RestoreState(in);
  own_state_->Read(in);
}

// The snapshot: {the parts' composite snapshot, a copy of the subclass's own state}.
std::unique_ptr<ObjectState> AggregateObject::NewObjectState() const {
  auto box = std::make_unique<CompositeState>();
  box->parts.push_back(parts_.NewSnapshot());
  box->parts.push_back(own_state_->New());
  return box;
}

void AggregateObject::CopyObjectState(ObjectState& into) const {
  CompositeState& box = CompositeState::Of(into);
  parts_.TakeSnapshot(*box.parts[0]);
  own_state_->Copy(*box.parts[1]);
}

void AggregateObject::SetObjectState(const ObjectState& from) {
  const CompositeState& box = CompositeState::Of(from);
  parts_.RestoreSnapshot(*box.parts[0]);
  own_state_->Set(*box.parts[1]);
}

bool AggregateObject::state_is_value() const {
  for (std::size_t i = 0; i < parts_.num_objects(); ++i)
    if (!parts_.object(i).state_is_value()) return false;
  for (std::size_t i = 0; i < parts_.num_connectors(); ++i)
    if (!parts_.connector(i).state_is_value()) return false;
  return true;
}

}  // namespace gipsi
