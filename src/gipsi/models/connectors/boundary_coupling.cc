#include "gipsi/models/connectors/boundary_coupling.h"

#include <cmath>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/region_json.h"

namespace gipsi {

BoundaryCoupling::BoundaryCoupling(std::string name, SimObject& driver, SimObject& follower,
                                   const std::optional<Region>& follower_region, double tolerance)
    : Connector(std::move(name)), driver_(driver), follower_(follower) {
  BindNoState();  // every Fire rewrites its buffers
  driver_displacement_ = driver.FindField("boundary_displacement");
  follower_reaction_ = follower.FindField("reaction_force");
  (void)driver.FindField("reaction_force");
  (void)follower.FindField("boundary_displacement");
  UseField("driver", driver, "boundary_displacement", FieldAccess::kRead, "m", 3);
  UseBoundaryConditions("driver", driver);
  UseField("follower", follower, "reaction_force", FieldAccess::kRead, "N", 3);
  UseBoundaryConditions("follower", follower);

  const BoundarySurface& db = driver.boundary();
  const BoundarySurface& fb = follower.boundary();
  Points driver_rest, follower_rest;
  db.Gather(driver.domain().nodes, driver_rest);
  fb.Gather(follower.domain().nodes, follower_rest);
  if (db.num_triangles() == 0 || fb.num_vertices() == 0)
    throw InputError(
        fmt::format("connector '{}': both objects need a boundary surface", this->path()));
  if (!(tolerance > 0)) {
    const Points& nodes = follower.domain().nodes;
    tolerance = 1e-6 * (nodes.rowwise().maxCoeff() - nodes.rowwise().minCoeff()).norm();
  }

  std::vector<int> candidates;
  if (follower_region) {
    candidates = SelectBoundaryVertices(*follower_region, follower.domain(), fb);
  } else {
    for (Index j = 0; j < fb.num_vertices(); ++j) candidates.push_back(static_cast<int>(j));
  }
  Points targets(3, static_cast<Index>(candidates.size()));
  for (std::size_t k = 0; k < candidates.size(); ++k)
    targets.col(static_cast<Index>(k)) = follower_rest.col(candidates[k]);
  PointMap probe = PointMap::BarycentricOnTriangles(driver_rest, db.triangles, targets);
  Points mapped(3, targets.cols());
  probe.Apply(driver_rest, mapped);
  Points kept(3, targets.cols());
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const auto col = static_cast<Index>(k);
    const double gap = (mapped.col(col) - targets.col(col)).norm();
    if (gap <= tolerance) {
      kept.col(static_cast<Index>(follower_vertices_.size())) = targets.col(col);
      follower_vertices_.push_back(candidates[k]);
    } else if (follower_region) {
      throw InputError(fmt::format(
          "connector '{}': follower boundary vertex {} (node {}) is {:.3g} from the driver's "
          "boundary, more than the tolerance {:.3g}",
          this->path(), candidates[k], fb.vertex_to_node[static_cast<std::size_t>(candidates[k])],
          gap, tolerance));
    }
  }
  if (follower_vertices_.empty())
    throw InputError(
        fmt::format("connector '{}': no boundary vertex of '{}' lies on the boundary "
                    "of '{}' (tolerance {:.3g}); the objects share no interface",
                    this->path(), follower.path(), driver.path(), tolerance));
  kept.conservativeResize(3, static_cast<Index>(follower_vertices_.size()));
  map_ = PointMap::BarycentricOnTriangles(driver_rest, db.triangles, kept);
  driver_u_.resize(3, db.num_vertices());
  interface_u_.resize(3, kept.cols());
  follower_r_.resize(3, fb.num_vertices());
}

StepStatus BoundaryCoupling::DoFire(double /*t*/) {
  driver_.ReadField(driver_displacement_, driver_u_);
  map_.Apply(driver_u_, interface_u_);
  BoundaryConditions& fbc = follower_.boundary_conditions();
  for (std::size_t k = 0; k < follower_vertices_.size(); ++k)
    fbc.PrescribeDisplacement(follower_vertices_[k], interface_u_.col(static_cast<Index>(k)));
  follower_.ReadField(follower_reaction_, follower_r_);
  BoundaryConditions& dbc = driver_.boundary_conditions();
  const auto& idx = map_.indices();
  const auto& w = map_.weights();
  for (std::size_t k = 0; k < follower_vertices_.size(); ++k) {
    const auto col = static_cast<Index>(k);
    const Vec3 r = follower_r_.col(follower_vertices_[k]);
    if (!r.allFinite()) return StepStatus::Diverged("non-finite reaction force at vertex", col);
    for (int s = 0; s < 4; ++s)
      if (w(s, col) != 0) dbc.AddCouplingForce(idx(s, col), -w(s, col) * r);
  }
  return StepStatus::Ok();
}

void RegisterBoundaryCoupling(TypeRegistry& registry) {
  registry.connectors.Register(
      "BoundaryCoupling",
      [](const ConnectorBuildContext& ctx) -> std::unique_ptr<Connector> {
        ctx.CheckKeys({"driver", "follower", "follower_region", "tolerance"});
        SimObject& driver = ctx.Object("driver");
        SimObject& follower = ctx.Object("follower");
        std::optional<Region> region;
        if (auto r = ctx.params.Find("follower_region")) region = ParseRegion(*r);
        try {
          return std::make_unique<BoundaryCoupling>(ctx.name, driver, follower, region,
                                                    ctx.params.Positive("tolerance", -1.0));
        } catch (const InputError& e) {
          ctx.params.Fail(e.what());
        }
      },
      "boundary coupling: driver displacement → follower constraint, reaction → driver force");
}

}  // namespace gipsi
