#pragma once
/// @file
/// `LocalModelTick`: the haptic tick against local dynamic models (local_model.h). Each tick it
/// reads the device, takes the newest published model if there is one (re-anchoring: the local
/// state is reset to the new anchor, and the difference between the force rendered last tick
/// and the new model's force is added as an offset that fades linearly to zero over
/// `blend_time`, so a hand-over never makes the force jump; the rendered force's normal part is
/// kept ≥ 0, a contact only pushes), steps the model for the device's
/// depth, passes the force through `ForceSafety`, commands the device, and publishes the tool
/// position and the contact force for the simulation (`HapticFeedback`). No allocation, locks,
/// exceptions or I/O.

#include <cstdint>

#include "gipsi/base/export.h"
#include "gipsi/haptics/haptic_tick.h"
#include "gipsi/haptics/local_model.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// What the haptic side hands back to the simulation. Plain struct.
struct HapticFeedback {
  Vec3 tool = Vec3::Zero();   ///< device position [m, simulation coordinates]
  Vec3 force = Vec3::Zero();  ///< force of the tool on the object at the contact node [N]
  int contact_vertex = -1;    ///< boundary vertex the force acts on (−1: none)
  double time = -1;           ///< haptic time of the tick [s]
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("tool", s.tool);
    v("force", s.force);
    v("contact_vertex", s.contact_vertex);
    v("time", s.time);
  }
};

/// What a LocalModelTick carries from one tick to the next (a state value type,
/// gipsi/base/state_value.h): the local state, the hand-over blend, the depth history, the
/// last outputs and the safety stage. The models it renders live in the buffer, which its
/// producer (HapticBridge) keeps.
struct LocalTickState {
  LocalVector u, v;  ///< the local displacements [m] and velocities [m/s]
  bool anchored = false, blend_pending = false, have_depth = false;
  double previous_depth = 0, depth = 0, proxy_depth = 0, model_force = 0, blend_left = 0;
  Vec3 rendered = Vec3::Zero(), offset = Vec3::Zero(), proxy = Vec3::Zero(), tool = Vec3::Zero();
  std::int64_t handovers = 0;
  ForceSafetyState safety;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("u", s.u);
    v("v", s.v);
    v("anchored", s.anchored);
    v("blend_pending", s.blend_pending);
    v("have_depth", s.have_depth);
    v("previous_depth", s.previous_depth);
    v("depth", s.depth);
    v("proxy_depth", s.proxy_depth);
    v("model_force", s.model_force);
    v("blend_left", s.blend_left);
    v("rendered", s.rendered);
    v("offset", s.offset);
    v("proxy", s.proxy);
    v("tool", s.tool);
    v("handovers", s.handovers);
    v("safety", s.safety);
  }
};

/// Parameters of the tick. Plain struct with defaults.
struct LocalTickParams {
  LocalCoupling coupling;    ///< device ↔ contact node
  double blend_time = 0.01;  ///< s, fade of the hand-over offset (about one simulation step)
  ForceSafetyParams safety;
};

/// Not copyable or movable (holds references to the device and the buffers).
class LocalModelTick final : public HapticRenderer {
 public:
  /// `feedback` may be null (nothing is handed back).
  LocalModelTick(HapticDevice& device, const DeviceWorkspace& workspace,
                 LatestValue<LocalDynamicModel>& models, LatestValue<HapticFeedback>* feedback,
                 const LocalTickParams& params);

  Vec3 Run(double t, double dt) noexcept override;

  /// Normal contact force of the local model in the last tick [N] (before blending, safety).
  [[nodiscard]] double model_force() const { return model_force_; }
  /// Force rendered in the last tick (model plus hand-over offset) [N, simulation coordinates].
  [[nodiscard]] const Vec3& rendered_force() const { return rendered_; }
  /// Device depth below the current model's tangent plane in the last tick [m].
  [[nodiscard]] double depth() const { return depth_; }
  /// Depth of the proxy (the local surface point) below that plane [m].
  [[nodiscard]] double proxy_depth() const { return proxy_depth_; }
  /// Proxy position [m, simulation coordinates].
  [[nodiscard]] const Vec3& proxy() const { return proxy_; }
  /// Device position read in the last tick [m, simulation coordinates].
  [[nodiscard]] const Vec3& tool_position() const { return tool_; }
  [[nodiscard]] const LocalState& state() const { return state_; }
  [[nodiscard]] const LocalDynamicModel& model() const { return models_.front(); }
  [[nodiscard]] const ForceSafety& safety() const { return safety_; }
  [[nodiscard]] std::int64_t num_handovers() const { return handovers_; }
  /// Checkpoints and roll-back (haptic_state.cc): everything the next ticks depend on.
  void GetState(LocalTickState& out) const;
  void SetState(const LocalTickState& in);

 private:
  HapticDevice& device_;
  DeviceWorkspace workspace_;
  LatestValue<LocalDynamicModel>& models_;
  LatestValue<HapticFeedback>* feedback_;
  LocalTickParams params_;
  ForceSafety safety_;
  LocalState state_;
  bool anchored_ = false, blend_pending_ = false, have_depth_ = false;
  double previous_depth_ = 0, depth_ = 0, proxy_depth_ = 0, model_force_ = 0;
  Vec3 rendered_ = Vec3::Zero(), offset_ = Vec3::Zero(), proxy_ = Vec3::Zero();
  Vec3 tool_ = Vec3::Zero();
  double blend_left_ = 0;
  std::int64_t handovers_ = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
