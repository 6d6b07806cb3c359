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

#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/connector.h"
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

 protected:
  StepStatus DoFire(double t) override;

 private:
  SimObject& driver_;
  SimObject& follower_;
  FieldId driver_displacement_, follower_reaction_;
  std::vector<int> follower_vertices_;
  PointMap map_;  // driver boundary vertices → interface vertices
  Eigen::MatrixXd driver_u_, interface_u_, follower_r_;
};

void RegisterBoundaryCoupling(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
