/// @file
/// Coordinator snapshots: one CompositeState with every object's snapshot, then every
/// connector's, in the coordinator's order.

#include "gipsi/base/error.h"
#include "gipsi/base/object_state.h"
#include "gipsi/core/coordinator.h"

namespace gipsi {

std::unique_ptr<ObjectState> Coordinator::NewSnapshot() const {
  auto box = std::make_unique<CompositeState>();
  for (std::size_t i = 0; i < num_objects(); ++i) box->parts.push_back(object(i).NewSnapshot());
  for (std::size_t i = 0; i < num_connectors(); ++i)
    box->parts.push_back(connector(i).NewSnapshot());
  return box;
}

void Coordinator::TakeSnapshot(ObjectState& into) const {
  CompositeState& box = CompositeState::Of(into);
  GIPSI_CHECK(box.parts.size() == num_objects() + num_connectors(),
              "a snapshot of another coordinator");
  for (std::size_t i = 0; i < num_objects(); ++i) object(i).TakeSnapshot(*box.parts[i]);
  for (std::size_t i = 0; i < num_connectors(); ++i)
    connector(i).TakeSnapshot(*box.parts[num_objects() + i]);
}

void Coordinator::RestoreSnapshot(const ObjectState& from) {
  const CompositeState& box = CompositeState::Of(from);
  GIPSI_CHECK(box.parts.size() == num_objects() + num_connectors(),
              "a snapshot of another coordinator");
  for (std::size_t i = 0; i < num_objects(); ++i) object(i).RestoreSnapshot(*box.parts[i]);
  for (std::size_t i = 0; i < num_connectors(); ++i)
    connector(i).RestoreSnapshot(*box.parts[num_objects() + i]);
}

}  // namespace gipsi
