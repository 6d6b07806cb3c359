#include "gipsi/haptics/haptic_tick.h"

namespace gipsi {

ProxyForce RenderPlane(const PlaneLocalModel& model, const Vec3& x) noexcept {
  ProxyForce out;
  out.proxy = x;
  if (!model.active) return out;
  const double depth = (model.point - x).dot(model.normal);  // > 0 below the plane
  if (depth > 0) {
    out.proxy = x + depth * model.normal;
    out.force = model.stiffness * (out.proxy - x);
  }
  return out;
}

HapticTick::HapticTick(HapticDevice& device, const DeviceWorkspace& workspace,
                       LatestValue<PlaneLocalModel>& models, const ForceSafetyParams& safety)
    : device_(device), workspace_(workspace), models_(models), safety_(safety) {}

Vec3 HapticTick::Run(double t, double dt) noexcept {
  const DevicePose pose = device_.Read(t);
  models_.Fetch();
  const PlaneLocalModel& model = models_.front();
  render_ = RenderPlane(model, workspace_.ToSimulation(pose.position));
  const Vec3 desired = workspace_.ForceToDevice(render_.force);
  const Vec3 force = safety_.Filter(desired, dt, t - model.published_at, pose.connected);
  device_.Command(force, Vec3::Zero());
  return force;
}

}  // namespace gipsi
