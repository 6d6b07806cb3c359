#pragma once
/// @file
/// `BoundaryCoupling`: couples two objects through a shared boundary (a Dirichlet–Neumann
/// partitioned exchange). The *driver*'s boundary displacement, interpolated on its boundary
/// triangles, is prescribed on the *follower*'s interface vertices; the follower's reaction
/// forces there are returned to the driver's boundary vertices with the transpose of the same
/// interpolation, so the total force is conserved exactly.
///
/// Scene: {"type": "BoundaryCoupling", "driver": "a", "follower": "b",
///         "follower_region": <region>, "tolerance": 1e-6}
/// Without a region, the interface is every follower boundary vertex within `tolerance` (default
/// 1e-6 of the follower's bounding-box diagonal) of the driver's boundary surface at rest.
/// Both objects must provide the fields "boundary_displacement" and "reaction_force".
///
/// In a distributed run either object may be made in blocks (gipsi/core/partitioned_object.h),
/// each process holding its part of the boundary. A follower in blocks takes, on each process,
/// its part's interface vertices, and returns the reactions of those whose node it owns; a
/// driver in blocks answers for the interface points through its parts' boundary faces, and its
/// parts' owners receive the spread forces (PartitionedObject::InterpolateOnBoundary). A whole
/// end is the same on every process: a whole driver's spread forces are summed over the
/// processes, a whole follower's reactions are spread once (each interface vertex by one
/// process). No process holds either boundary whole for it.

#include <memory>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/connector.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/core/registry.h"
#include "gipsi/geometry/mapping.h"
#include "gipsi/geometry/region.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable or movable.
class BoundaryCoupling final : public Connector {
 public:
  /// Throws InputError if a field is missing, no interface vertex is found, or a vertex of the
  /// given region is farther than `tolerance` from the driver's boundary.
  BoundaryCoupling(std::string name, SimObject& driver, SimObject& follower,
                   const std::optional<Region>& follower_region, double tolerance);

  [[nodiscard]] std::string_view type_name() const override { return "BoundaryCoupling"; }
  /// Follower boundary vertices on the interface.
  [[nodiscard]] const std::vector<int>& interface_vertices() const { return follower_vertices_; }
  /// Whether either end is made in blocks (the run then couples parts, each process its own).
  [[nodiscard]] bool couples_parts() const override { return agree_on_ != nullptr; }

 protected:
  StepStatus DoFire(double t) override;

 private:
  SimObject& driver_;
  SimObject& follower_;
  FieldId driver_displacement_, follower_reaction_;
  std::vector<int> follower_vertices_;
  PointMap map_;  // driver boundary vertices → interface vertices (a whole driver)
  // A driver in blocks: its parts answer for this process's interface vertices.
  std::unique_ptr<BoundaryInterpolation> parts_;
  // The object the processes agree through (a split end's), when either end is in blocks.
  const PartitionedObject* agree_on_ = nullptr;
  // Per interface vertex: whether this process returns its reaction (a follower in blocks: the
  // vertex's node is this process's; a whole follower with a driver in blocks: one process
  // each); all of them when neither end is in blocks.
  std::vector<char> returns_;
  bool sum_driver_forces_ = false;  // a whole driver's forces summed over the processes
  Eigen::MatrixXd driver_u_, interface_u_, follower_r_, interface_f_, driver_f_;
};

void RegisterBoundaryCoupling(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
