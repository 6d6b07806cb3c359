#pragma once
/// @file
/// `IgtlDevice`: a haptic device driven over OpenIGTLink (protocol 2, Debian libopenigtlink 1.11),
/// e.g. by a tracker or 3D Slicer. It connects as a TCP client, takes the pose from TRANSFORM
/// messages of one device name, and can send a triangle surface back as a POLYDATA message (so
/// Slicer shows the deformed organ). All networking runs on the device's own thread: the
/// haptic thread's `Read` only takes the newest pose from a lock-free triple buffer
/// (latest_value.h), so a slow or dead network never blocks a haptic tick. When the connection
/// is lost `Read` reports `connected = false` (the watchdog in ForceSafety then fades the force)
/// and the thread tries to reconnect every `reconnect_interval`.
///
/// Units: a TRANSFORM's translation is in message units (Slicer: mm); the device position is
/// translation · `length_unit` [m] (default 0.001). POLYDATA points are float32(x / length_unit).

#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "gipsi/base/export.h"
#include "gipsi/base/latest_value.h"
#include "gipsi/haptics/device.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Connection parameters. Plain struct with defaults.
struct IgtlDeviceParams {
  std::string host = "127.0.0.1";    ///< server address (IPv4 dotted quad or a host name)
  int port = 18944;                  ///< TCP port (OpenIGTLink's default)
  std::string device_name = "Tool";  ///< TRANSFORM messages of other names are ignored
  double length_unit = 0.001;        ///< m per message length unit
  double connect_timeout = 2;        ///< s, for the first connection (the constructor waits)
  double reconnect_interval = 0.5;   ///< s between attempts after a lost connection
};

/// A triangle surface to send, in simulation coordinates. Plain struct.
struct IgtlSurface {
  std::string name;                       ///< POLYDATA device name
  Points positions = Points(3, 0);        ///< 3 by V [m]
  Triangles triangles = Triangles(3, 0);  ///< 3 by T vertex indices
};

/// Not copyable or movable (its thread refers to it).
class IgtlDevice final : public HapticDevice {
 public:
  /// Connects to params.host:params.port, waiting up to `connect_timeout`, and starts the
  /// network thread. Throws InputError naming the address when the host cannot be resolved or
  /// nothing accepts the connection in time, and for bad parameters (port outside 1–65535,
  /// non-positive length unit or intervals, empty device name).
  explicit IgtlDevice(const IgtlDeviceParams& params);
  ~IgtlDevice() override;

  /// The newest pose received (position [m, device coordinates] and orientation); before the
  /// first TRANSFORM and while disconnected, `connected` is false. `t` is not used. Wait-free.
  DevicePose Read(double t) noexcept override;
  /// Keeps the force for inspection (OpenIGTLink has no standard force message). Wait-free.
  void Command(const Vec3& force, const Vec3& torque) noexcept override;

  /// Simulation side: queues `surface` for sending as POLYDATA; only the newest queued surface
  /// is sent (a slow link drops frames instead of piling them up). Allocates; never blocks on
  /// the network. One producer thread only.
  void SendSurface(const Points& positions, const Triangles& triangles, const std::string& name);

  [[nodiscard]] const IgtlDeviceParams& params() const { return params_; }
  /// Whether the socket is connected now (any thread).
  [[nodiscard]] bool connected() const { return connected_.load(); }
  /// TRANSFORM messages accepted so far (any thread).
  [[nodiscard]] std::int64_t num_poses() const { return poses_received_.load(); }
  /// POLYDATA messages sent so far (any thread).
  [[nodiscard]] std::int64_t num_surfaces_sent() const { return surfaces_sent_.load(); }
  /// Connections lost so far (any thread).
  [[nodiscard]] std::int64_t num_disconnects() const { return disconnects_.load(); }
  [[nodiscard]] const Vec3& last_force() const { return force_; }

 private:
  struct Connection;
  void Run();
  bool ReceiveOne();
  bool SendPending();
  void Disconnect();

  IgtlDeviceParams params_;
  std::unique_ptr<Connection> connection_;  // network thread only (after construction)
  LatestValue<DevicePose> poses_;           // network thread → haptic thread
  LatestValue<IgtlSurface> surfaces_;       // simulation thread → network thread
  DevicePose latest_;                       // haptic thread
  DevicePose received_;                     // network thread: last pose received
  Vec3 force_ = Vec3::Zero(), torque_ = Vec3::Zero();
  std::atomic<bool> stop_{false}, connected_{false};
  std::atomic<std::int64_t> poses_received_{0}, surfaces_sent_{0}, disconnects_{0};
  std::thread thread_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
