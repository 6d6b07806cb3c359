#pragma once
/// @file
/// Haptic devices: pose (position, orientation) and buttons in, force and torque out. A device
/// lives in its own coordinates; `DeviceWorkspace` maps them to the simulation's. Reading and
/// commanding run on the haptic thread: they never throw, lock or allocate.

#include <cstdint>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// What a device reports in one tick. Plain struct.
struct DevicePose {
  Vec3 position = Vec3::Zero();  ///< device coordinates [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  std::uint32_t buttons = 0;  ///< bit i set: button i pressed
  bool connected = true;      ///< false once the device stopped answering
};

/// Maps device coordinates to simulation coordinates, x_sim = offset + scale · x_device, and
/// forces back with the power-consistent factor: f_device = scale · f_sim (so f · dx is the same
/// on both sides, which keeps a passive simulated contact passive at the device). Plain struct.
struct DeviceWorkspace {
  double scale = 1;
  Vec3 offset = Vec3::Zero();
  [[nodiscard]] Vec3 ToSimulation(const Vec3& device_position) const {
    return offset + scale * device_position;
  }
  [[nodiscard]] Vec3 ForceToDevice(const Vec3& simulation_force) const {
    return scale * simulation_force;
  }
};

/// A haptic device. Not copyable or movable (it usually owns a connection).
class HapticDevice {
 public:
  HapticDevice() = default;
  HapticDevice(const HapticDevice&) = delete;
  HapticDevice& operator=(const HapticDevice&) = delete;
  virtual ~HapticDevice() = default;

  /// The pose at time `t` [s] of the haptic clock. Never throws, locks or allocates.
  virtual DevicePose Read(double t) noexcept = 0;
  /// Commands a force [N] and torque [N·m] in device coordinates. Never throws, locks or
  /// allocates.
  virtual void Command(const Vec3& force, const Vec3& torque) noexcept = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
