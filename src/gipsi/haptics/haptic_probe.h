#pragma once
/// @file
/// Multi-rate haptics in scene files:
///  - `HapticProbe` (object): a haptic device — a virtual one on a scripted path, a mouse in the
///    viewer (`MouseDevice`), or an OpenIGTLink client (`IgtlDevice`) — rendering local models
///    with a `LocalModelTick` at `rate`. By default the probe's step runs the ticks over the
///    step, synchronously (headless runs are then deterministic). With "realtime" the ticks run
///    in a `HapticLoop` on their own thread, on the wall clock, while the simulation runs
///    (`RealtimeHaptics`, realtime_haptics.h, starts and stops the loop with the run); the
///    probe's step then only reads the loop's newest outputs into its fields and keeps the
///    simulation from running ahead of the wall clock. Fields (global, read): "tool_force"
///    (force on the device [N]), "tool_position" [m], "proxy_position" [m] (the god-object on
///    the local surface), "model_force" (the local model's normal contact force [N]).
///  - `HapticCoupling` (connector): joins a deformable object and a probe through a
///    `HapticBridge`: when it fires it applies the newest tool force to the object (boundary
///    condition) and publishes a local model built at the object's current state
///    (`FemCondensation` for FemSolid, `MassSpringNeighbourhood` for MassSpring). Building a
///    model allocates (a factorisation for FEM), unlike other connectors' firings.
///
/// Scene:
///   "probe": {"type": "HapticProbe", "path": [[t, x, y, z], ...], "rate": 1000,
///             "coupling_stiffness": 5000, "coupling_damping": 0, "blend_time": 0.01,
///             "max_force": 3, "max_rate": 1000, "stale_after": 0.05, "fade_time": 0.1,
///             "workspace_scale": 1, "workspace_offset": [0, 0, 0],
///             "realtime": {"fifo": false, "priority": 80, "cpu": -1, "spin": 0}}
///             (or "realtime": true)
///   or, instead of "path", "device": {"type": "OpenIGTLink", "host": "127.0.0.1",
///             "port": 18944, "name": "Tool", "length_unit": 0.001, "connect_timeout": 2,
///             "reconnect_interval": 0.5}
///   or "device": {"type": "Mouse", "start": [x, y, z], "wheel_step": 0.002}
///   "haptics": {"type": "HapticCoupling", "object": "liver", "device": "probe",
///               "capture_distance": 0.01, "rings": 1}

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string_view>

#include "gipsi/core/connector.h"
#include "gipsi/core/pacing.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"

#include "gipsi/base/export.h"
#include "gipsi/haptics/haptic_bridge.h"
#include "gipsi/haptics/haptic_endpoint.h"
#include "gipsi/haptics/haptic_loop.h"
#include "gipsi/haptics/igtl_device.h"
#include "gipsi/haptics/mouse_device.h"
#include "gipsi/haptics/virtual_device.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Parameters of a HapticProbe. Plain struct with defaults.
struct HapticProbeSpec {
  /// Virtual device: positions [m, device coordinates]; used when `igtl` and `mouse` are empty.
  std::vector<DeviceKeyframe> path;
  /// OpenIGTLink device: connection parameters (the path is then unused).
  std::optional<IgtlDeviceParams> igtl;
  /// Mouse device (the viewer moves it; the path is then unused).
  std::optional<MouseDeviceParams> mouse;
  DeviceWorkspace workspace;  ///< device → simulation coordinates
  double rate = 1000;         ///< haptic ticks per second
  LocalTickParams tick;
  /// Run the ticks in a real-time HapticLoop with this scheduling (none: synchronously).
  std::optional<HapticRealtime> realtime;
};

/// What a synchronous HapticProbe carries from one step to the next (a state value type,
/// gipsi/base/state_value.h): its fields, the tick count, the scripted device's and, once a
/// HapticCoupling attached it, the tick's state.
struct HapticProbeState {
  static constexpr std::string_view kTag = "HapticProbe";
  static constexpr std::uint32_t kVersion = 1;
  Vec3 force = Vec3::Zero(), position = Vec3::Zero(), proxy = Vec3::Zero();
  double model_force = 0;
  std::int64_t ticks = 0;
  VirtualDeviceState device;
  bool coupled = false;  ///< whether `tick` is in use
  LocalTickState tick;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("force", s.force);
    v("position", s.position);
    v("proxy", s.proxy);
    v("model_force", s.model_force);
    v("ticks", s.ticks);
    v("device", s.device);
    v("coupled", s.coupled);
    v("tick", s.tick);
  }
};

/// Not copyable or movable (a SimObject).
class HapticProbe final : public SimObject, public WallClockPaced, public HapticEndpoint {
 public:
  /// Throws InputError for an empty or non-increasing path, a rate outside (0, 10 kHz] or an
  /// OpenIGTLink device that cannot connect (IgtlDevice's constructor).
  HapticProbe(std::string name, const HapticProbeSpec& spec);
  /// Stops the real-time loop if it runs.
  ~HapticProbe() override;

  [[nodiscard]] std::string_view type_name() const override { return "HapticProbe"; }
  [[nodiscard]] const Points& domain_positions() const override { return no_positions_; }
  [[nodiscard]] const HapticProbeSpec& spec() const { return spec_; }
  /// The device's position when the probe was built [m, simulation coordinates].
  [[nodiscard]] const Vec3& initial_position() const override { return initial_; }
  /// The OpenIGTLink device, or null for another kind.
  [[nodiscard]] IgtlDevice* igtl_device() override { return igtl_; }
  /// The mouse device, or null for another kind.
  [[nodiscard]] MouseDevice* mouse_device() { return mouse_; }
  /// Connects the probe to a bridge's buffers (once; the HapticCoupling connector does it).
  /// Throws InputError if it is already connected.
  void Attach(LatestValue<LocalDynamicModel>& models,
              LatestValue<HapticFeedback>& feedback) override;
  [[nodiscard]] bool attached() const { return tick_ != nullptr; }
  /// Number of haptic ticks run so far (for a real-time probe: as of its last step).
  [[nodiscard]] std::int64_t num_ticks() const { return ticks_; }

  /// Whether the probe ticks in a real-time HapticLoop (scene key "realtime").
  [[nodiscard]] bool realtime() const override { return spec_.realtime.has_value(); }
  /// Ticks per second (scene key "rate").
  [[nodiscard]] double haptic_rate() const override { return spec_.rate; }
  /// Starts the real-time loop with the haptic clock at `sim_time` [s] (RealtimeHaptics does
  /// it when a run starts). Preconditions (checked, abort): realtime(), the loop is not running.
  void StartLoop(double sim_time) override;
  /// Stops and joins the real-time loop and returns its statistics (all zero for a loop that
  /// never ran). Idempotent; does nothing for a synchronous probe.
  HapticLoopStats StopLoop() override;
  /// Whether the real-time loop runs.
  [[nodiscard]] bool loop_running() const override { return loop_ && loop_->running(); }
  /// The haptic clock at simulation time `sim_time` [s]: `sim_time` itself for a synchronous
  /// probe; for a real-time one with its loop running, the simulation time the loop started at
  /// plus the wall-clock seconds since (models are stamped with it, so their age is real).
  [[nodiscard]] double HapticTime(double sim_time) const override;
  /// The haptic clock (HapticTime) while the real-time loop runs: the probe is never stepped
  /// past it, the coordinator waits for it (gipsi/core/pacing.h). +infinity otherwise.
  [[nodiscard]] double WallClockTime(double sim_time) const override {
    return loop_running() ? HapticTime(sim_time) : std::numeric_limits<double>::infinity();
  }
  /// The renderer the real-time loop ticks (null for a synchronous probe). Exposed so a test
  /// can tick it on its own thread while the loop is stopped (e.g. under an allocation guard).
  [[nodiscard]] HapticRenderer* loop_renderer();

  /// Checkpoints and roll-back (haptic_state.cc) of a synchronous probe on a scripted path: a
  /// HapticProbeState, gathered from the probe, its device and its tick (BindGatheredState). A
  /// real-time probe (ticks on the wall clock), a Mouse or an OpenIGTLink device (moved by a
  /// person or a tracker) makes a run that cannot be reproduced: InputError saying so.
  void GetState(HapticProbeState& out) const;
  void SetState(const HapticProbeState& in);

 protected:
  StepStatus DoStep(double t, double dt) override;
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;

 private:
  class LoopRenderer;
  /// What the loop hands to the probe's step after every tick. Plain struct.
  struct Sample {
    Vec3 force = Vec3::Zero(), position = Vec3::Zero(), proxy = Vec3::Zero();
    double model_force = 0;
    std::int64_t ticks = 0;
  };
  /// The step of a real-time probe: reads the loop's newest sample.
  StepStatus StepRealtime();

  HapticProbeSpec spec_;
  std::unique_ptr<HapticDevice> device_;
  IgtlDevice* igtl_ = nullptr;        // device_, when it is an OpenIGTLink device
  MouseDevice* mouse_ = nullptr;      // device_, when it is a mouse device
  VirtualDevice* virtual_ = nullptr;  // device_, when it is a scripted virtual device
  Vec3 initial_ = Vec3::Zero();
  std::unique_ptr<LocalModelTick> tick_;
  Points no_positions_ = Points(3, 0);
  Vec3 force_ = Vec3::Zero(), position_ = Vec3::Zero(), proxy_ = Vec3::Zero();
  double model_force_ = 0;
  std::int64_t ticks_ = 0;
  FieldId f_force_, f_position_, f_proxy_, f_model_force_;
  // Real-time mode (declared last: the loop stops first).
  double loop_origin_ = 0;  // simulation time at which the loop started
  std::unique_ptr<LatestValue<Sample>> samples_;
  std::unique_ptr<LoopRenderer> renderer_;
  std::unique_ptr<HapticLoop> loop_;
};

/// Not copyable or movable (a Connector).
class HapticCoupling final : public Connector {
 public:
  /// Renders the local models `builder` makes of its object (see LocalModels,
  /// gipsi/core/local_model.h) on `device`, an object with the HapticEndpoint capability (a
  /// HapticProbe): attaches the device to the bridge and publishes a first model at the
  /// object's current state. The bridge's period is the device's (`params.period` is
  /// overwritten). Throws InputError if the object has no boundary surface or the device is
  /// not a HapticEndpoint or already coupled.
  HapticCoupling(std::string name, std::unique_ptr<LocalModelBuilder> builder, SimObject& device,
                 HapticBridgeParams params);
  [[nodiscard]] std::string_view type_name() const override { return "HapticCoupling"; }
  /// Stops the device's real-time loop (it reads this connector's buffers).
  ~HapticCoupling() override;
  [[nodiscard]] HapticBridge& bridge() { return *bridge_; }

 protected:
  StepStatus DoFire(double t) override;

 private:
  SimObject& device_;
  HapticEndpoint& endpoint_;
  std::unique_ptr<LocalModelBuilder> builder_;
  std::unique_ptr<HapticBridge> bridge_;
};

/// Registers the object "HapticProbe" and the connectors "HapticCoupling" and
/// "OpenIGTLinkSurface" (igtl_surface_sender.h).
void RegisterHaptics(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
