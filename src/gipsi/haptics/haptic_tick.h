#pragma once
/// @file
/// One tick of haptic rendering against the simplest local model an object can publish: the
/// tangent plane at the contact with a local stiffness (Çavuşoğlu & Tendick's local geometric
/// model with a zeroth-order local dynamic model). A god-object (proxy) stays on the plane while
/// the device is below it; the force is k (proxy − x). `HapticTick` reads the device, fetches
/// the latest published model from a lock-free buffer, renders, passes the force through
/// `ForceSafety` and commands the device: no locks, no exceptions, no allocation.
/// `HapticRenderer` is what the haptic loop ticks; `LocalModelTick` (local_model_tick.h)
/// renders the local dynamic models.

#include "gipsi/base/export.h"
#include "gipsi/base/latest_value.h"
#include "gipsi/haptics/device.h"
#include "gipsi/haptics/force_safety.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A tangent plane with a stiffness, published by the simulation. Plain struct.
struct PlaneLocalModel {
  Vec3 point = Vec3::Zero();     ///< a point of the plane [m, simulation coordinates]
  Vec3 normal = Vec3::UnitZ();   ///< unit, pointing out of the object
  double stiffness = 0;          ///< N/m
  double published_at = -1e300;  ///< simulation time of publication [s]
  bool active = false;           ///< false: no contact is possible (free motion)
};

/// Proxy and force for a device at x (simulation coordinates) against a plane model. Plain.
struct ProxyForce {
  Vec3 proxy = Vec3::Zero();
  Vec3 force = Vec3::Zero();  ///< on the device [N, simulation coordinates]
};

/// The god-object on a plane: the proxy is x when x is above the plane, else x projected onto
/// it; the force is stiffness · (proxy − x).
ProxyForce RenderPlane(const PlaneLocalModel& model, const Vec3& x) noexcept;

/// One tick of a haptic renderer, run by `HapticLoop` on the haptic thread. Not copyable.
class HapticRenderer {
 public:
  HapticRenderer() = default;
  HapticRenderer(const HapticRenderer&) = delete;
  HapticRenderer& operator=(const HapticRenderer&) = delete;
  virtual ~HapticRenderer() = default;
  /// Runs one tick at haptic time `t` [s] with period `dt` [s]; returns the force commanded
  /// [N, device coordinates]. No allocation, locks, exceptions or I/O.
  virtual Vec3 Run(double t, double dt) noexcept = 0;
};

/// Not copyable or movable (holds references to the device and the buffer).
class HapticTick final : public HapticRenderer {
 public:
  HapticTick(HapticDevice& device, const DeviceWorkspace& workspace,
             LatestValue<PlaneLocalModel>& models, const ForceSafetyParams& safety);

  /// Runs one tick at haptic time `t` [s] with period `dt` [s]; the model's age is t minus its
  /// publication time. Returns the force commanded [N, device coordinates].
  Vec3 Run(double t, double dt) noexcept override;

  [[nodiscard]] const ProxyForce& last_render() const { return render_; }
  [[nodiscard]] const ForceSafety& safety() const { return safety_; }

 private:
  HapticDevice& device_;
  DeviceWorkspace workspace_;
  LatestValue<PlaneLocalModel>& models_;
  ForceSafety safety_;
  ProxyForce render_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
