#pragma once
/// @file
/// `VirtualDevice`: a haptic device that replays a scripted trajectory, for headless runs and
/// tests. Positions are interpolated linearly between keyframes and held outside them; the
/// commanded forces are kept for inspection.

#include <cstdint>
#include <filesystem>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/haptics/device.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// What a VirtualDevice carries from one tick to the next (a state value type,
/// gipsi/base/state_value.h); its pose is a function of time.
struct VirtualDeviceState {
  bool connected = true;
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();  ///< the last command
  std::int64_t commands = 0;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("connected", s.connected);
    v("force", s.force);
    v("torque", s.torque);
    v("commands", s.commands);
  }
};

/// One keyframe of a trajectory. Plain struct.
struct DeviceKeyframe {
  double time = 0;  ///< s
  Vec3 position = Vec3::Zero();
  std::uint32_t buttons = 0;
};

/// Not copyable or movable (a HapticDevice).
class VirtualDevice final : public HapticDevice {
 public:
  /// Keyframe times must increase strictly; throws InputError otherwise or when empty.
  explicit VirtualDevice(std::vector<DeviceKeyframe> path);
  /// Reads a trajectory file: one keyframe per line, `t, x, y, z` or `t, x, y, z, buttons`
  /// (commas or spaces); blank lines, lines starting with '#' and a first line that is not
  /// numeric (a header) are skipped. Throws InputError naming the file and line.
  static std::vector<DeviceKeyframe> ReadTrajectory(const std::filesystem::path& file);

  DevicePose Read(double t) noexcept override;
  void Command(const Vec3& force, const Vec3& torque) noexcept override;

  /// Simulates a disconnection (Read then reports connected = false) or a reconnection.
  void SetConnected(bool connected) { connected_ = connected; }
  [[nodiscard]] const Vec3& last_force() const { return force_; }
  [[nodiscard]] const Vec3& last_torque() const { return torque_; }
  [[nodiscard]] std::int64_t num_commands() const { return commands_; }
  /// Checkpoints and roll-back: the connection flag and the commands received.
  [[nodiscard]] VirtualDeviceState state() const {
    return {connected_, force_, torque_, commands_};
  }
  void set_state(const VirtualDeviceState& s) {
    connected_ = s.connected;
    force_ = s.force;
    torque_ = s.torque;
    commands_ = s.commands;
  }

 private:
  std::vector<DeviceKeyframe> path_;
  bool connected_ = true;
  Vec3 force_ = Vec3::Zero(), torque_ = Vec3::Zero();
  std::int64_t commands_ = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
