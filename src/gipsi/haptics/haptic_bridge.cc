#include "gipsi/haptics/haptic_bridge.h"

#include <cmath>
#include <limits>

#include "gipsi/base/error.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/geometry/normals.h"

namespace gipsi {

HapticBridge::HapticBridge(LocalModelBuilder& builder, const HapticBridgeParams& params)
    : builder_(builder),
      params_(params),
      models_(std::make_unique<LatestValue<LocalDynamicModel>>()),
      feedback_(std::make_unique<LatestValue<HapticFeedback>>()) {
  GIPSI_CHECK(params.period > 0 && params.capture_distance >= 0, "bad HapticBridgeParams");
}

Vec3 HapticBridge::ApplyFeedback() {
  if (feedback_->Fetch()) latest_ = feedback_->front();
  BoundaryConditions& bcs = builder_.object().boundary_conditions();
  if (applied_vertex_ >= 0) bcs.SetForce(applied_vertex_, Vec3::Zero());
  applied_vertex_ = -1;
  if (latest_.contact_vertex < 0 || latest_.contact_vertex >= bcs.num_vertices() ||
      !latest_.force.allFinite())
    return Vec3::Zero();
  applied_vertex_ = latest_.contact_vertex;
  bcs.SetForce(applied_vertex_, latest_.force);
  return latest_.force;
}

bool HapticBridge::Publish(double now) {
  SimObject& object = builder_.object();
  const BoundarySurface& bnd = object.boundary();
  const bool pushing = latest_.contact_vertex >= 0 && latest_.contact_vertex == contact_ &&
                       latest_.force.squaredNorm() > 0;
  double anchor_force = 0;
  if (pushing) {
    anchor_force = std::max(0.0, -latest_.force.dot(normal_));
  } else {
    contact_ = -1;
    bnd.Gather(object.domain_positions(), boundary_positions_);
    double best = std::numeric_limits<double>::infinity();
    for (Index j = 0; j < bnd.num_vertices(); ++j) {
      const double d = (boundary_positions_.col(j) - latest_.tool).squaredNorm();
      if (d < best) {
        best = d;
        contact_ = j;
      }
    }
    if (contact_ >= 0 && std::sqrt(best) <= params_.capture_distance) {
      VertexNormals(boundary_positions_, bnd.triangles, normals_);
      normal_ = normals_.col(contact_);
      if (!(normal_.squaredNorm() > 0)) contact_ = -1;
    } else {
      contact_ = -1;
    }
  }
  LocalDynamicModel& model = models_->back();
  bool active = false;
  if (contact_ >= 0)
    active = builder_.Build(contact_, normal_, anchor_force, params_.period, model);
  if (!active) {
    model.active = false;
    contact_ = -1;
  }
  model.published_at = now;
  models_->Publish();
  return active;
}

}  // namespace gipsi
