#include "gipsi/haptics/mouse_device.h"

#include <cmath>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi {

std::optional<Vec3> RayPlanePoint(const Vec3& origin, const Vec3& direction,
                                  const Vec3& plane_point, const Vec3& plane_normal) {
  const Vec3 d = direction.normalized(), n = plane_normal.normalized();
  const double cosine = d.dot(n);
  if (!(std::abs(cosine) >= 1e-9)) return std::nullopt;  // parallel (or a zero vector: NaN)
  const double s = (plane_point - origin).dot(n) / cosine;
  if (!(s > 0)) return std::nullopt;
  return origin + s * d;
}

namespace {
DevicePose StartPose(const MouseDeviceParams& params) {
  DevicePose pose;
  pose.position = params.start;
  return pose;
}
}  // namespace

MouseDevice::MouseDevice(const MouseDeviceParams& params)
    : params_(params), pose_(StartPose(params)), poses_(pose_), forces_(Vec3::Zero()) {
  if (!params.start.allFinite())
    throw InputError("mouse device: the start position must be finite");
  if (!(params.wheel_step > 0 && std::isfinite(params.wheel_step)))
    throw InputError(
        fmt::format("mouse device: wheel step {} m must be positive", params.wheel_step));
}

void MouseDevice::BeginDrag(const Vec3& view_direction) {
  if (!(view_direction.norm() > 0) || !view_direction.allFinite()) return;
  plane_point_ = pose_.position;
  plane_normal_ = view_direction.normalized();
  dragging_ = true;
}

bool MouseDevice::DragTo(const Vec3& ray_origin, const Vec3& ray_direction) {
  if (!dragging_) return false;
  const std::optional<Vec3> point =
      RayPlanePoint(ray_origin, ray_direction, plane_point_, plane_normal_);
  if (!point || !point->allFinite()) return false;
  pose_.position = *point;
  HandOver();
  return true;
}

void MouseDevice::Push(const Vec3& view_direction, double notches) {
  if (!(view_direction.norm() > 0) || !view_direction.allFinite() || !std::isfinite(notches))
    return;
  const Vec3 step = notches * params_.wheel_step * view_direction.normalized();
  pose_.position += step;
  plane_point_ += step;
  HandOver();
}

void MouseDevice::SetButtons(std::uint32_t buttons) {
  pose_.buttons = buttons;
  HandOver();
}

const Vec3& MouseDevice::TakeForce() {
  forces_.Fetch();
  return forces_.front();
}

void MouseDevice::HandOver() {
  poses_.back() = pose_;
  poses_.Publish();
}

DevicePose MouseDevice::Read(double /*t*/) noexcept {
  poses_.Fetch();
  return poses_.front();
}

void MouseDevice::Command(const Vec3& force, const Vec3& /*torque*/) noexcept {
  forces_.back() = force;
  forces_.Publish();
}

}  // namespace gipsi
