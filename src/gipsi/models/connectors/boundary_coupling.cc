#include "gipsi/models/connectors/boundary_coupling.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
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

  // Ends made in blocks (a distributed run): their boundary is this process's part's.
  const auto* driver_split = dynamic_cast<const PartitionedObject*>(&driver);
  const auto* follower_split = dynamic_cast<const PartitionedObject*>(&follower);
  const bool driver_parts = driver_split != nullptr && !driver_split->holds_whole_domain();
  const bool follower_parts = follower_split != nullptr && !follower_split->holds_whole_domain();
  agree_on_ = driver_parts ? driver_split : follower_parts ? follower_split : nullptr;
  auto combine = [](const PartitionedObject* over, double value, PartitionedObject::Combine how) {
    if (over != nullptr) over->CombineAcross(std::span<double>(&value, 1), how);
    return value;
  };
  const PartitionedObject* driver_over = driver_parts ? driver_split : nullptr;
  const PartitionedObject* follower_over = follower_parts ? follower_split : nullptr;
  using Combine = PartitionedObject::Combine;

  const BoundarySurface& db = driver.boundary();
  const BoundarySurface& fb = follower.boundary();
  Points driver_rest, follower_rest;
  db.Gather(driver.domain().nodes, driver_rest);
  fb.Gather(follower.domain().nodes, follower_rest);
  if (combine(driver_over, static_cast<double>(db.num_triangles()), Combine::kSum) == 0 ||
      combine(follower_over, static_cast<double>(fb.num_vertices()), Combine::kSum) == 0)
    throw InputError(
        fmt::format("connector '{}': both objects need a boundary surface", this->path()));
  if (!(tolerance > 0)) {
    const Points& nodes = follower.domain().nodes;
    tolerance =
        1e-6 * (follower_parts ? follower_split->WholeDiagonal()
                               : (nodes.rowwise().maxCoeff() - nodes.rowwise().minCoeff()).norm());
  }

  std::vector<int> candidates;
  if (follower_region && follower_parts) {
    candidates = follower_split->SelectConditionItems(*follower_region, false).items;
  } else if (follower_region) {
    candidates = SelectBoundaryVertices(*follower_region, follower.domain(), fb);
  } else {
    for (Index j = 0; j < fb.num_vertices(); ++j) candidates.push_back(static_cast<int>(j));
  }
  Points targets(3, static_cast<Index>(candidates.size()));
  for (std::size_t k = 0; k < candidates.size(); ++k)
    targets.col(static_cast<Index>(k)) = follower_rest.col(candidates[k]);
  // How far each candidate lies from the driver's boundary: on its parts' faces, or its own.
  std::vector<double> gaps(candidates.size());
  if (driver_parts) {
    const std::unique_ptr<BoundaryInterpolation> probe =
        driver_split->InterpolateOnBoundary(targets);
    std::copy(probe->distances().begin(), probe->distances().end(), gaps.begin());
  } else {
    PointMap probe = PointMap::BarycentricOnTriangles(driver_rest, db.triangles, targets);
    Points mapped(3, targets.cols());
    probe.Apply(driver_rest, mapped);
    for (std::size_t k = 0; k < candidates.size(); ++k)
      gaps[k] = (mapped.col(static_cast<Index>(k)) - targets.col(static_cast<Index>(k))).norm();
  }
  // The follower's whole node of a candidate (its index on its whole mesh).
  auto whole_node = [&](std::size_t k) {
    const int node = fb.vertex_to_node[static_cast<std::size_t>(candidates[k])];
    return follower_parts ? follower_split->whole_nodes_of_part()[static_cast<std::size_t>(node)]
                          : node;
  };
  if (follower_region) {
    // The first vertex of the region off the driver's boundary, by its whole node (the same
    // on every process when the follower is in blocks).
    double first = std::numeric_limits<double>::infinity(), gap = 0;
    for (std::size_t k = 0; k < candidates.size(); ++k)
      if (gaps[k] > tolerance && whole_node(k) < first) {
        first = whole_node(k);
        gap = gaps[k];
      }
    if (follower_parts) {
      const double mine = first;
      first = combine(follower_over, first, Combine::kMin);
      gap = combine(follower_over, mine == first ? gap : 0.0, Combine::kMax);
    }
    if (std::isfinite(first))
      throw InputError(fmt::format(
          "connector '{}': follower boundary vertex at node {} is {:.3g} from the driver's "
          "boundary, more than the tolerance {:.3g}",
          this->path(), static_cast<std::int64_t>(first), gap, tolerance));
  }
  Points kept(3, targets.cols());
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    if (gaps[k] > tolerance) continue;
    kept.col(static_cast<Index>(follower_vertices_.size())) = targets.col(static_cast<Index>(k));
    follower_vertices_.push_back(candidates[k]);
  }
  if (combine(follower_over, static_cast<double>(follower_vertices_.size()), Combine::kSum) == 0)
    throw InputError(
        fmt::format("connector '{}': no boundary vertex of '{}' lies on the boundary "
                    "of '{}' (tolerance {:.3g}); the objects share no interface",
                    this->path(), follower.path(), driver.path(), tolerance));
  kept.conservativeResize(3, static_cast<Index>(follower_vertices_.size()));
  // Which reactions this process returns: each interface vertex's once over the processes.
  for (std::size_t k = 0; k < follower_vertices_.size(); ++k) {
    const int node = fb.vertex_to_node[static_cast<std::size_t>(follower_vertices_[k])];
    returns_.push_back(follower_parts ? node < follower_split->num_owned_nodes()
                       : driver_parts ? static_cast<int>(k % static_cast<std::size_t>(
                                                                 driver_split->num_processes())) ==
                                            driver_split->process()
                                      : true);
  }
  if (driver_parts) {
    parts_ = driver_split->InterpolateOnBoundary(kept);
  } else {
    map_ = PointMap::BarycentricOnTriangles(driver_rest, db.triangles, kept);
    driver_u_.resize(3, db.num_vertices());
  }
  sum_driver_forces_ = !driver_parts && follower_parts;
  interface_u_.resize(3, kept.cols());
  interface_f_.resize(3, kept.cols());
  follower_r_.resize(3, fb.num_vertices());
  driver_f_.resize(3, db.num_vertices());
  if (agree_on_ != nullptr)
    Log().debug("{}: couples the boundaries' parts, each process its own", this->path());
}

StepStatus BoundaryCoupling::DoFire(double /*t*/) {
  if (parts_) {
    parts_->Interpolate(driver_displacement_, interface_u_, std::nullopt);
  } else {
    driver_.ReadField(driver_displacement_, driver_u_);
    map_.Apply(driver_u_, interface_u_);
  }
  BoundaryConditions& fbc = follower_.boundary_conditions();
  for (std::size_t k = 0; k < follower_vertices_.size(); ++k)
    fbc.PrescribeDisplacement(follower_vertices_[k], interface_u_.col(static_cast<Index>(k)));
  follower_.ReadField(follower_reaction_, follower_r_);
  BoundaryConditions& dbc = driver_.boundary_conditions();
  if (agree_on_ == nullptr) {  // both whole: the serial coupling
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
  // An end in blocks: the reactions this process returns, the first non-finite one agreed on
  // every process (by interface vertex) so that all stop alike.
  double bad = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < follower_vertices_.size(); ++k) {
    const auto col = static_cast<Index>(k);
    interface_f_.col(col).setZero();
    if (returns_[k] == 0) continue;
    const Vec3 r = follower_r_.col(follower_vertices_[k]);
    if (!r.allFinite() && std::isinf(bad)) bad = static_cast<double>(k);
    interface_f_.col(col) = -r;
  }
  agree_on_->CombineAcross(std::span<double>(&bad, 1), PartitionedObject::Combine::kMin);
  if (std::isfinite(bad))
    return StepStatus::Diverged("non-finite reaction force at vertex",
                                static_cast<std::int64_t>(bad));
  if (parts_) {
    parts_->Spread(interface_f_, driver_f_);
  } else {  // a whole driver: this process's share, summed over the processes
    driver_f_.setZero();
    const auto& idx = map_.indices();
    const auto& w = map_.weights();
    for (Index k = 0; k < interface_f_.cols(); ++k)
      for (int s = 0; s < 4; ++s)
        if (w(s, k) != 0) driver_f_.col(idx(s, k)) += w(s, k) * interface_f_.col(k);
    agree_on_->CombineAcross(std::span<double>(driver_f_.data(), driver_f_.size()),
                             PartitionedObject::Combine::kSum);
  }
  for (Index v = 0; v < driver_f_.cols(); ++v)
    if (!driver_f_.col(v).isZero(0)) dbc.AddCouplingForce(v, driver_f_.col(v));
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
  // Either end may be made in blocks: a driver's parts answer for the interface vertices, a
  // follower's parts take their own (and the other end may be whole).
  registry.connector_part_use["BoundaryCoupling"] = [](const JsonNode&) {
    return TypeRegistry::PartUse::kAnyParts;
  };
}

}  // namespace gipsi
