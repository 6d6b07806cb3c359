#pragma once
/// @file
/// `HapticBridge`: the simulation side of multi-rate haptics for one object. Around each of the
/// object's steps it (1) takes the latest `HapticFeedback` from the haptic loop and applies the
/// tool's force to the object as a boundary condition (an applied nodal force on the contact
/// vertex, replacing the one it applied before), and (2) after the step picks the contact
/// vertex and the tangent plane at the object's new state, builds a local dynamic model there
/// with a `LocalModelBuilder`, and publishes it through the lock-free buffer the haptic loop
/// reads. The haptic loop never touches the object.
///
/// Contact vertex: while the tool pushes (non-zero force) the vertex and its normal are kept;
/// otherwise the boundary vertex nearest to the tool is taken if it lies within
/// `capture_distance`, with its area-weighted outward normal at the current state; farther away
/// an inactive model is published (free motion).

#include <array>
#include <cstdint>
#include <memory>
#include <string_view>

#include "gipsi/base/export.h"
#include "gipsi/base/latest_value.h"
#include "gipsi/core/local_model.h"
#include "gipsi/haptics/local_model.h"
#include "gipsi/haptics/local_model_tick.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Parameters. Plain struct with defaults.
struct HapticBridgeParams {
  double period = 1e-3;            ///< haptic period the models are discretised for [s]
  double capture_distance = 0.01;  ///< m, see the file comment
};

/// A LatestValue's contents (gipsi/base/latest_value.h) as a value: the three slots in index
/// order, which side holds which slot, and whether the exchanged slot holds an unfetched value.
template <class T>
struct LatestValueSlots {
  std::array<T, 3> slots;
  std::array<std::int32_t, 3> roles = {0, 1, 2};  ///< back, middle, front
  bool fresh = false;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("slots", s.slots);
    v("roles", s.roles);
    v("fresh", s.fresh);
  }
};

/// What a HapticBridge carries from one firing to the next (a state value type,
/// gipsi/base/state_value.h): the feedback taken, the contact kept, the vertex carrying the tool
/// force, and both buffers whole (all three slots and their layout, so that a model published
/// but not yet fetched is handed over as it would have been).
struct HapticBridgeState {
  static constexpr std::string_view kTag = "HapticBridge";
  static constexpr std::uint32_t kVersion = 2;
  HapticFeedback latest;
  std::int64_t applied_vertex = -1, contact = -1;
  Vec3 normal = Vec3::UnitZ();
  LatestValueSlots<LocalDynamicModel> models;
  LatestValueSlots<HapticFeedback> feedback;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("latest", s.latest);
    v("applied_vertex", s.applied_vertex);
    v("contact", s.contact);
    v("normal", s.normal);
    v("models", s.models);
    v("feedback", s.feedback);
  }
};

/// Not copyable or movable (the haptic loop holds references to its buffers).
class HapticBridge {
 public:
  HapticBridge(LocalModelBuilder& builder, const HapticBridgeParams& params);
  HapticBridge(const HapticBridge&) = delete;
  HapticBridge& operator=(const HapticBridge&) = delete;

  /// Before the object's step: applies the newest feedback force. Returns the force applied [N].
  Vec3 ApplyFeedback();
  /// After the object's step: builds and publishes a model stamped with time `now` [s] (on the
  /// haptic loop's clock). Returns whether the published model is active.
  bool Publish(double now);

  /// Where the tool is until the first feedback arrives (e.g. the device's initial position),
  /// so the first published model can already be active.
  void SeedTool(const Vec3& position) { latest_.tool = position; }

  /// The buffers the haptic side uses.
  [[nodiscard]] LatestValue<LocalDynamicModel>& models() { return *models_; }
  [[nodiscard]] LatestValue<HapticFeedback>& feedback() { return *feedback_; }
  /// The newest feedback taken by ApplyFeedback.
  [[nodiscard]] const HapticFeedback& last_feedback() const { return latest_; }
  /// Contact vertex of the last published model (−1: none).
  [[nodiscard]] Index contact_vertex() const { return contact_; }
  [[nodiscard]] LocalModelBuilder& builder() { return builder_; }
  /// Checkpoints and roll-back (haptic_state.cc), only while the haptic side does not run (a
  /// synchronous probe). SetState throws InputError, changing nothing, for a state that does
  /// not fit this object (a contact vertex it does not have, a buffer layout that is not a
  /// permutation, a model whose arrays disagree with its size).
  void GetState(HapticBridgeState& out) const;
  void SetState(const HapticBridgeState& in);

 private:
  LocalModelBuilder& builder_;
  HapticBridgeParams params_;
  std::unique_ptr<LatestValue<LocalDynamicModel>> models_;
  std::unique_ptr<LatestValue<HapticFeedback>> feedback_;
  HapticFeedback latest_;
  Index applied_vertex_ = -1, contact_ = -1;
  Vec3 normal_ = Vec3::UnitZ();
  Points boundary_positions_, normals_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
