/// @file
/// AggregateObject checkpoints: every part, then every connector, in the coordinator's order.

#include "gipsi/base/state.h"
#include "gipsi/core/aggregate.h"

namespace gipsi {

void AggregateObject::SaveObjectState(StateWriter& out) const {
  out.WriteInt(static_cast<std::int64_t>(parts_.num_objects()));
  out.WriteInt(static_cast<std::int64_t>(parts_.num_connectors()));
  for (std::size_t i = 0; i < parts_.num_objects(); ++i) parts_.object(i).SaveState(out);
  for (std::size_t i = 0; i < parts_.num_connectors(); ++i) parts_.connector(i).SaveState(out);
}

void AggregateObject::RestoreObjectState(StateReader& in) {
  if (in.ReadInt() != static_cast<std::int64_t>(parts_.num_objects()) ||
      in.ReadInt() != static_cast<std::int64_t>(parts_.num_connectors()))
    in.Fail("the aggregate has a different number of parts or connectors in the checkpoint");
  for (std::size_t i = 0; i < parts_.num_objects(); ++i) parts_.object(i).RestoreState(in);
  for (std::size_t i = 0; i < parts_.num_connectors(); ++i) parts_.connector(i).RestoreState(in);
}

}  // namespace gipsi
