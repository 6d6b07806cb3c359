#pragma once
/// @file
/// `MassSpringNeighbourhood`: MassSpring's haptic local model (gipsi/core/local_model.h). The
/// contact node and the nodes within a few rings of springs move, the next ring is held fixed;
/// mass, damping and tangent stiffness of the springs are linearised at the current state. Nodes
/// with a constrained axis count as fixed. Registered for "MassSpring" by RegisterMassSpring.

#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/local_model.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class MassSpring;

/// Neighbourhood model of a MassSpring object.
class MassSpringNeighbourhood final : public LocalModelBuilder {
 public:
  /// `rings` ≥ 0: spring rings around the contact node that move (capped at kMaxLocalNodes
  /// nodes, nearest rings first; the nodes left out are held fixed).
  MassSpringNeighbourhood(MassSpring& object, int rings = 1);
  [[nodiscard]] SimObject& object() override;
  bool Build(Index vertex, const Vec3& normal, double anchor_force, double period,
             LocalDynamicModel& out) override;
  /// Domain nodes of the last model (contact node first).
  [[nodiscard]] const std::vector<int>& local_nodes() const { return local_; }

 private:
  MassSpring& object_;
  int rings_;
  std::vector<std::vector<int>> node_springs_;  // springs at each node
  std::vector<int> local_index_;                // node → local index or −1
  std::vector<int> local_;
  VecX xdot_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
