/// @file
/// Checkpoints and roll-back of multi-rate haptics. A synchronous probe on a scripted path is
/// deterministic, so its run can be continued bit for bit. That needs more than the fields: the
/// tick's local state and hand-over blend, the safety stage, the bridge's kept contact, and both
/// lock-free buffers whole. An inactive model only overwrites `active` and `published_at` of its
/// slot, and the tick still reads the slot's normal, so what every slot holds, and which side
/// holds it, influences the future. The states are value types (HapticProbeState,
/// HapticBridgeState) gathered from the parts that keep them live (BindGatheredState): this file
/// copies them in and out, and checks a value before it replaces anything.

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/haptics/haptic_bridge.h"
#include "gipsi/haptics/haptic_probe.h"
#include "gipsi/haptics/local_model_tick.h"

namespace gipsi {

namespace {

/// Throws InputError, with the reason, for a probe whose run cannot be reproduced.
void RefuseUnreproducible(const std::string& probe, bool realtime, bool igtl, bool mouse) {
  const char* why = realtime ? "it is real-time (\"realtime\"): its ticks follow the wall clock"
                    : igtl   ? "its OpenIGTLink device is moved by a tracker"
                    : mouse  ? "its Mouse device is moved by the viewer's user"
                             : nullptr;
  if (why != nullptr)
    throw InputError(fmt::format(
        "haptic probe '{}' cannot be checkpointed or rolled back: {}, so the run cannot be "
        "reproduced (a probe on a scripted \"path\" can)",
        probe, why));
}

template <class T>
void GetSlots(const LatestValue<T>& buffer, LatestValueSlots<T>& out) {
  const auto layout = buffer.layout();
  out.roles = {layout.back, layout.middle, layout.front};
  out.fresh = layout.fresh;
  for (int i = 0; i < 3; ++i) out.slots[static_cast<std::size_t>(i)] = buffer.slot(i);
}

template <class T>
typename LatestValue<T>::Layout LayoutOf(const LatestValueSlots<T>& s) {
  typename LatestValue<T>::Layout layout;
  layout.back = s.roles[0];
  layout.middle = s.roles[1];
  layout.front = s.roles[2];
  layout.fresh = s.fresh;
  return layout;
}

/// Whether the three roles are a permutation of the slots 0, 1, 2.
bool IsPermutation(const std::array<std::int32_t, 3>& roles) {
  int seen = 0;
  for (std::int32_t r : roles) {
    if (r < 0 || r > 2) return false;
    seen |= 1 << r;
  }
  return seen == 7;
}

template <class T>
void SetSlots(const LatestValueSlots<T>& s, LatestValue<T>& buffer) {
  for (int i = 0; i < 3; ++i) buffer.slot(i) = s.slots[static_cast<std::size_t>(i)];
  const bool ok = buffer.set_layout(LayoutOf(s));
  GIPSI_CHECK(ok, "a buffer layout that was checked");
}

/// Why a local model cannot be rendered as it is, or "" if it can: a model is discretised
/// whole (DiscretiseLocalModel), so every array has 3m rows.
std::string ModelProblem(const LocalDynamicModel& m) {
  if (m.num_nodes < 0 || m.num_nodes > kMaxLocalNodes)
    return fmt::format("a local model has {} nodes (at most {})", m.num_nodes, kMaxLocalNodes);
  const Index n = m.dofs();
  bool consistent = m.step_v.cols() == n && m.step_u.cols() == n && m.stiffness.cols() == n;
  for (Index rows :
       {m.step_v.rows(), m.step_u.rows(), m.stiffness.rows(), m.step_bias.size(), m.gain.size(),
        m.push.size(), m.initial_velocity.size(), m.mass.size(), m.load.size()})
    consistent = consistent && rows == n;
  return consistent
             ? std::string()
             : fmt::format("a local model of {} nodes has arrays of other sizes", m.num_nodes);
}

}  // namespace

// --- The haptic side ---

void LocalModelTick::GetState(LocalTickState& out) const {
  out.u = state_.u;
  out.v = state_.v;
  out.anchored = anchored_;
  out.blend_pending = blend_pending_;
  out.have_depth = have_depth_;
  out.previous_depth = previous_depth_;
  out.depth = depth_;
  out.proxy_depth = proxy_depth_;
  out.model_force = model_force_;
  out.blend_left = blend_left_;
  out.rendered = rendered_;
  out.offset = offset_;
  out.proxy = proxy_;
  out.tool = tool_;
  out.handovers = handovers_;
  out.safety = safety_.state();
}

void LocalModelTick::SetState(const LocalTickState& in) {
  state_.u = in.u;
  state_.v = in.v;
  anchored_ = in.anchored;
  blend_pending_ = in.blend_pending;
  have_depth_ = in.have_depth;
  previous_depth_ = in.previous_depth;
  depth_ = in.depth;
  proxy_depth_ = in.proxy_depth;
  model_force_ = in.model_force;
  blend_left_ = in.blend_left;
  rendered_ = in.rendered;
  offset_ = in.offset;
  proxy_ = in.proxy;
  tool_ = in.tool;
  handovers_ = in.handovers;
  safety_.set_state(in.safety);
}

// --- The simulation side ---

void HapticBridge::GetState(HapticBridgeState& out) const {
  out.latest = latest_;
  out.applied_vertex = applied_vertex_;
  out.contact = contact_;
  out.normal = normal_;
  GetSlots(*models_, out.models);
  GetSlots(*feedback_, out.feedback);
}

void HapticBridge::SetState(const HapticBridgeState& in) {
  const Index vertices = builder_.object().boundary().num_vertices();
  for (Index v : {static_cast<Index>(in.applied_vertex), static_cast<Index>(in.contact),
                  static_cast<Index>(in.latest.contact_vertex)})
    if (v < -1 || v >= vertices)
      throw InputError(
          fmt::format("contact vertex {} of a surface with {} vertices: the state was written "
                      "for another scene",
                      v, vertices));
  if (!IsPermutation(in.models.roles))
    throw InputError("the local model buffer's layout is corrupted");
  if (!IsPermutation(in.feedback.roles))
    throw InputError("the feedback buffer's layout is corrupted");
  for (const LocalDynamicModel& m : in.models.slots)
    if (std::string problem = ModelProblem(m); !problem.empty()) throw InputError(problem);
  latest_ = in.latest;
  applied_vertex_ = in.applied_vertex;
  contact_ = in.contact;
  normal_ = in.normal;
  SetSlots(in.models, *models_);
  SetSlots(in.feedback, *feedback_);
}

void HapticProbe::GetState(HapticProbeState& out) const {
  RefuseUnreproducible(name(), realtime(), igtl_ != nullptr, mouse_ != nullptr);
  out.force = force_;
  out.position = position_;
  out.proxy = proxy_;
  out.model_force = model_force_;
  out.ticks = ticks_;
  out.device = virtual_->state();
  out.coupled = tick_ != nullptr;
  if (tick_) tick_->GetState(out.tick);
}

void HapticProbe::SetState(const HapticProbeState& in) {
  RefuseUnreproducible(name(), realtime(), igtl_ != nullptr, mouse_ != nullptr);
  if (in.coupled != (tick_ != nullptr))
    throw InputError(
        fmt::format("haptic probe '{}' is {} in this scene but was not in the saved state", path(),
                    tick_ ? "coupled to an object" : "not coupled"));
  force_ = in.force;
  position_ = in.position;
  proxy_ = in.proxy;
  model_force_ = in.model_force;
  ticks_ = in.ticks;
  virtual_->set_state(in.device);
  if (tick_) tick_->SetState(in.tick);
}

}  // namespace gipsi
