#pragma once
/// @file
/// `HapticEndpoint`: the capability of an object that renders an object's local models on a
/// haptic device at its own rate (multi-rate haptics, docs/haptics.md). The `HapticCoupling`
/// connector and `RealtimeHaptics` reach the device side through it, never through a concrete
/// type, so a plugin's device object (another kind of hardware, another tick) couples the same
/// way as the built-in `HapticProbe`.

#include "gipsi/base/export.h"
#include "gipsi/base/latest_value.h"
#include "gipsi/base/math.h"
#include "gipsi/core/local_model.h"
#include "gipsi/haptics/haptic_loop.h"
#include "gipsi/haptics/local_model_tick.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class IgtlDevice;
class SimObject;

/// The device side of multi-rate haptics. The bridge (HapticBridge, owned by the coupling)
/// publishes local models into one lock-free buffer and reads the device's feedback from
/// another; the endpoint ticks the models against its device, on the simulation's thread
/// (synchronously, in its steps) or on its own real-time loop.
class HapticEndpoint {
 public:
  virtual ~HapticEndpoint() = default;
  /// Ticks per second: the local models are discretised for this period.
  [[nodiscard]] virtual double haptic_rate() const = 0;
  /// Where the device's tool was when the object was built [m, simulation coordinates].
  [[nodiscard]] virtual const Vec3& initial_position() const = 0;
  /// Connects to a bridge's buffers, once; throws InputError if already connected.
  virtual void Attach(LatestValue<LocalDynamicModel>& models,
                      LatestValue<HapticFeedback>& feedback) = 0;
  /// The haptic clock at simulation time `sim_time` [s] (models are stamped with it).
  [[nodiscard]] virtual double HapticTime(double sim_time) const = 0;
  /// Whether it ticks on a real-time loop of its own (then RealtimeHaptics starts and stops
  /// it with the run, and the run is not reproducible).
  [[nodiscard]] virtual bool realtime() const = 0;
  /// Starts the real-time loop with the haptic clock at `sim_time` (realtime() only).
  virtual void StartLoop(double sim_time) = 0;
  /// Stops and joins the real-time loop, returning its statistics. Idempotent; nothing to do
  /// without a loop. The coupling calls it before its buffers go.
  virtual HapticLoopStats StopLoop() = 0;
  [[nodiscard]] virtual bool loop_running() const = 0;
  /// The OpenIGTLink connection, for connectors that send to the same peer (null: none).
  [[nodiscard]] virtual IgtlDevice* igtl_device() { return nullptr; }
};

/// `object` as a HapticEndpoint; throws InputError naming the object and its type otherwise.
HapticEndpoint& HapticEndpointOf(SimObject& object);

}  // namespace gipsi
GIPSI_EXPORT_END
