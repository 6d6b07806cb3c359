#pragma once
/// @file
/// `MouseDevice`: the "virtual device that follows the mouse in the viewer". The viewer's GUI
/// thread moves the tool with the mouse and hands the newest pose to the haptic side through a
/// `LatestValue` (wait-free); the force the haptic side commands goes back the same way, for
/// display. The device works in scene coordinates (no workspace mapping). The mouse maps to the
/// tool so: a drag moves the tool in the plane through the tool's position at the start of the
/// drag that faces the viewer (the pick ray's point on that plane), and the wheel pushes the
/// tool along the view direction by `wheel_step` per notch (away from the viewer for positive
/// notches), moving the drag plane with it. Without a viewer (headless runs) nothing moves the
/// tool: it stays at its start position.

#include <cstdint>
#include <optional>

#include "gipsi/base/export.h"
#include "gipsi/base/latest_value.h"
#include "gipsi/haptics/device.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Parameters of a MouseDevice. Plain struct with defaults.
struct MouseDeviceParams {
  Vec3 start = Vec3::Zero();  ///< the tool's position until the mouse moves it [m]
  double wheel_step = 0.002;  ///< tool travel per wheel notch [m]
};

/// Where the ray origin + s·direction (s > 0) meets the plane through `plane_point` with normal
/// `plane_normal`; std::nullopt when the ray is parallel to the plane (|cos| < 1e-9) or the
/// plane lies behind the origin.
std::optional<Vec3> RayPlanePoint(const Vec3& origin, const Vec3& direction,
                                  const Vec3& plane_point, const Vec3& plane_normal);

/// Not copyable or movable (a HapticDevice). The GUI-side methods are for one thread at a time
/// (the producer of the pose buffer and consumer of the force buffer); `Read` and `Command` for
/// the thread that ticks the probe (the haptic loop, or the simulation for a synchronous probe).
class MouseDevice final : public HapticDevice {
 public:
  /// Throws InputError for a non-finite start or a non-positive or non-finite wheel step.
  explicit MouseDevice(const MouseDeviceParams& params);

  // --- GUI thread ---
  /// Starts a drag in the plane through the tool's current position with normal
  /// `view_direction` (the camera's forward direction; need not be unit).
  void BeginDrag(const Vec3& view_direction);
  /// Moves the tool to where the pick ray meets the drag plane and hands the pose over. Does
  /// nothing outside a drag or when the ray misses the plane. Returns whether the tool moved.
  bool DragTo(const Vec3& ray_origin, const Vec3& ray_direction);
  /// Ends the drag; the tool stays where it is.
  void EndDrag() { dragging_ = false; }
  /// Moves the tool `notches` wheel steps along `view_direction` (normalised here; positive:
  /// away from the viewer) and hands the pose over; during a drag the plane moves along.
  void Push(const Vec3& view_direction, double notches);
  /// Sets the buttons reported with the pose (bit i: button i) and hands the pose over.
  void SetButtons(std::uint32_t buttons);
  /// The tool's position as last handed over [m, scene coordinates].
  [[nodiscard]] const Vec3& position() const { return pose_.position; }
  /// Whether a drag is in progress (BeginDrag without EndDrag since).
  [[nodiscard]] bool dragging() const { return dragging_; }
  /// The newest force commanded by the haptic side [N] (zero before the first command).
  [[nodiscard]] const Vec3& TakeForce();
  /// The parameters it was built with.
  [[nodiscard]] const MouseDeviceParams& params() const { return params_; }

  // --- haptic side ---
  /// The newest pose handed over (wait-free; no allocation).
  DevicePose Read(double t) noexcept override;
  /// Hands the force over for display; the torque is dropped.
  void Command(const Vec3& force, const Vec3& torque) noexcept override;

 private:
  void HandOver();
  MouseDeviceParams params_;
  // GUI side
  DevicePose pose_;
  bool dragging_ = false;
  Vec3 plane_point_ = Vec3::Zero(), plane_normal_ = Vec3::UnitZ();
  // hand-over
  LatestValue<DevicePose> poses_;
  LatestValue<Vec3> forces_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
