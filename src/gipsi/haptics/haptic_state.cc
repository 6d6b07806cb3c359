/// @file
/// Checkpoints and roll-back of multi-rate haptics (gipsi/base/state.h). A synchronous probe on
/// a scripted path is deterministic, so its run can be continued bit for bit. That needs more
/// than the fields: the tick's local state and hand-over blend, the safety stage, the bridge's
/// kept contact, and both lock-free buffers whole. An inactive model only overwrites `active`
/// and `published_at` of its slot, and the tick still reads the slot's normal, so what every
/// slot holds, and which side holds it, influences the future.

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/haptics/haptic_bridge.h"
#include "gipsi/haptics/haptic_probe.h"
#include "gipsi/haptics/local_model_tick.h"
#include "gipsi/haptics/virtual_device.h"

namespace gipsi {

namespace {

void WriteVec3(StateWriter& out, const Vec3& v) { out.WriteMatrix(v); }

Vec3 ReadVec3(StateReader& in, std::string_view what) {
  Vec3 v;
  in.ReadMatrixExact(v, what);
  return v;
}

/// Reads a matrix with inline storage (LocalMatrix, LocalVector) whose size must fit it: a
/// corrupted size is refused instead of overrunning the storage.
template <class M>
void ReadBounded(StateReader& in, M& out, std::string_view what) {
  Eigen::MatrixXd m;
  in.ReadMatrix(m);
  if (m.rows() > M::MaxRowsAtCompileTime || m.cols() > M::MaxColsAtCompileTime ||
      (M::ColsAtCompileTime == 1 && m.cols() != 1 && m.size() > 0))
    in.Fail(fmt::format("{} is {} by {}, larger than a local model can be ({} by {})", what,
                        m.rows(), m.cols(), static_cast<int>(M::MaxRowsAtCompileTime),
                        static_cast<int>(M::MaxColsAtCompileTime)));
  if (M::ColsAtCompileTime == 1)
    out.resize(m.rows(), 1);
  else
    out.resize(m.rows(), m.cols());
  if (m.size() > 0) out = m;
}

void WriteModel(StateWriter& out, const LocalDynamicModel& m) {
  out.WriteBool(m.active);
  out.WriteDouble(m.published_at);
  out.WriteDouble(m.period);
  WriteVec3(out, m.point);
  WriteVec3(out, m.normal);
  out.WriteDouble(m.anchor_force);
  out.WriteInt(m.contact_vertex);
  out.WriteInt(m.num_nodes);
  for (const LocalMatrix* a : {&m.step_v, &m.step_u, &m.stiffness}) out.WriteMatrix(*a);
  for (const LocalVector* a :
       {&m.step_bias, &m.gain, &m.push, &m.initial_velocity, &m.mass, &m.load})
    out.WriteMatrix(*a);
  out.WriteDouble(m.compliance);
}

void ReadModel(StateReader& in, LocalDynamicModel& m) {
  m.active = in.ReadBool();
  m.published_at = in.ReadDouble();
  m.period = in.ReadDouble();
  m.point = ReadVec3(in, "a local model's point");
  m.normal = ReadVec3(in, "a local model's normal");
  m.anchor_force = in.ReadDouble();
  m.contact_vertex = static_cast<int>(in.ReadInt());
  const std::int64_t nodes = in.ReadInt();
  if (nodes < 0 || nodes > kMaxLocalNodes)
    in.Fail(fmt::format("a local model has {} nodes (at most {})", nodes, kMaxLocalNodes));
  m.num_nodes = static_cast<int>(nodes);
  ReadBounded(in, m.step_v, "a local model's step matrix");
  ReadBounded(in, m.step_u, "a local model's step matrix");
  ReadBounded(in, m.stiffness, "a local model's stiffness");
  for (LocalVector* a : {&m.step_bias, &m.gain, &m.push, &m.initial_velocity, &m.mass, &m.load})
    ReadBounded(in, *a, "a local model's vector");
  m.compliance = in.ReadDouble();
  // A model is discretised whole (DiscretiseLocalModel): every array has 3m rows.
  const Index n = m.dofs();
  bool consistent = m.step_v.cols() == n && m.step_u.cols() == n && m.stiffness.cols() == n;
  for (Index rows :
       {m.step_v.rows(), m.step_u.rows(), m.stiffness.rows(), m.step_bias.size(), m.gain.size(),
        m.push.size(), m.initial_velocity.size(), m.mass.size(), m.load.size()})
    consistent = consistent && rows == n;
  if (!consistent)
    in.Fail(fmt::format("a local model of {} nodes has arrays of other sizes", m.num_nodes));
}

void WriteFeedback(StateWriter& out, const HapticFeedback& f) {
  WriteVec3(out, f.tool);
  WriteVec3(out, f.force);
  out.WriteInt(f.contact_vertex);
  out.WriteDouble(f.time);
}

void ReadFeedback(StateReader& in, HapticFeedback& f) {
  f.tool = ReadVec3(in, "the tool position");
  f.force = ReadVec3(in, "the tool force");
  f.contact_vertex = static_cast<int>(in.ReadInt());
  f.time = in.ReadDouble();
}

/// A LatestValue whole: its layout, then the three slots in index order.
template <class T, class Write>
void WriteBuffer(StateWriter& out, const LatestValue<T>& buffer, Write write) {
  const auto layout = buffer.layout();
  out.WriteArray(std::vector<std::int32_t>{layout.back, layout.middle, layout.front});
  out.WriteBool(layout.fresh);
  for (int i = 0; i < 3; ++i) write(out, buffer.slot(i));
}

template <class T, class Read>
void ReadBuffer(StateReader& in, LatestValue<T>& buffer, Read read, std::string_view what) {
  std::vector<std::int32_t> indices;
  in.ReadArray(indices);
  if (indices.size() != 3) in.Fail(fmt::format("the {} buffer's layout is corrupted", what));
  typename LatestValue<T>::Layout layout;
  layout.back = indices[0];
  layout.middle = indices[1];
  layout.front = indices[2];
  layout.fresh = in.ReadBool();
  // Slots first, layout last: a refused layout leaves the buffer's slot roles unchanged.
  for (int i = 0; i < 3; ++i) read(in, buffer.slot(i));
  if (!buffer.set_layout(layout)) in.Fail(fmt::format("the {} buffer's layout is corrupted", what));
}

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

}  // namespace

// --- The haptic side ---

void ForceSafety::SaveState(StateWriter& out) const {
  out.BeginSection("ForceSafety", 1);
  out.WriteDouble(gain_);
  WriteVec3(out, last_);
  out.WriteInt(limited_);
  out.EndSection();
}

void ForceSafety::RestoreState(StateReader& in) {
  in.BeginSection("ForceSafety", 1);
  gain_ = in.ReadDouble();
  last_ = ReadVec3(in, "the last commanded force");
  limited_ = in.ReadInt();
  in.EndSection();
}

void LocalModelTick::SaveState(StateWriter& out) const {
  out.BeginSection("LocalModelTick", 1);
  out.WriteMatrix(state_.u);
  out.WriteMatrix(state_.v);
  for (bool b : {anchored_, blend_pending_, have_depth_}) out.WriteBool(b);
  for (double x : {previous_depth_, depth_, proxy_depth_, model_force_, blend_left_})
    out.WriteDouble(x);
  for (const Vec3* v : {&rendered_, &offset_, &proxy_, &tool_}) WriteVec3(out, *v);
  out.WriteInt(handovers_);
  safety_.SaveState(out);
  out.EndSection();
}

void LocalModelTick::RestoreState(StateReader& in) {
  in.BeginSection("LocalModelTick", 1);
  ReadBounded(in, state_.u, "the local displacements");
  ReadBounded(in, state_.v, "the local velocities");
  for (bool* b : {&anchored_, &blend_pending_, &have_depth_}) *b = in.ReadBool();
  for (double* x : {&previous_depth_, &depth_, &proxy_depth_, &model_force_, &blend_left_})
    *x = in.ReadDouble();
  for (Vec3* v : {&rendered_, &offset_, &proxy_, &tool_}) *v = ReadVec3(in, "a tick vector");
  handovers_ = in.ReadInt();
  safety_.RestoreState(in);
  in.EndSection();
}

void VirtualDevice::SaveState(StateWriter& out) const {
  out.BeginSection("VirtualDevice", 1);
  out.WriteBool(connected_);
  WriteVec3(out, force_);
  WriteVec3(out, torque_);
  out.WriteInt(commands_);
  out.EndSection();
}

void VirtualDevice::RestoreState(StateReader& in) {
  in.BeginSection("VirtualDevice", 1);
  connected_ = in.ReadBool();
  force_ = ReadVec3(in, "the commanded force");
  torque_ = ReadVec3(in, "the commanded torque");
  commands_ = in.ReadInt();
  in.EndSection();
}

// --- The simulation side ---

void HapticBridge::SaveState(StateWriter& out) const {
  out.BeginSection("HapticBridge", 1);
  WriteFeedback(out, latest_);
  out.WriteInt(applied_vertex_);
  out.WriteInt(contact_);
  WriteVec3(out, normal_);
  WriteBuffer(out, *models_, WriteModel);
  WriteBuffer(out, *feedback_, WriteFeedback);
  out.EndSection();
}

void HapticBridge::RestoreState(StateReader& in) {
  in.BeginSection("HapticBridge", 1);
  ReadFeedback(in, latest_);
  applied_vertex_ = in.ReadInt();
  contact_ = in.ReadInt();
  const Index vertices = builder_.object().boundary().num_vertices();
  for (Index v : {applied_vertex_, contact_, static_cast<Index>(latest_.contact_vertex)})
    if (v < -1 || v >= vertices)
      in.Fail(
          fmt::format("contact vertex {} of a surface with {} vertices: the checkpoint was "
                      "written for another scene",
                      v, vertices));
  normal_ = ReadVec3(in, "the contact normal");
  ReadBuffer(in, *models_, ReadModel, "local model");
  ReadBuffer(in, *feedback_, ReadFeedback, "feedback");
  in.EndSection();
}

void HapticProbe::SaveObjectState(StateWriter& out) const {
  RefuseUnreproducible(name(), realtime(), igtl_ != nullptr, mouse_ != nullptr);
  WriteVec3(out, force_);
  WriteVec3(out, position_);
  WriteVec3(out, proxy_);
  out.WriteDouble(model_force_);
  out.WriteInt(ticks_);
  virtual_->SaveState(out);
  out.WriteBool(tick_ != nullptr);
  if (tick_) tick_->SaveState(out);
}

void HapticProbe::RestoreObjectState(StateReader& in) {
  RefuseUnreproducible(name(), realtime(), igtl_ != nullptr, mouse_ != nullptr);
  force_ = ReadVec3(in, "the tool force");
  position_ = ReadVec3(in, "the tool position");
  proxy_ = ReadVec3(in, "the proxy position");
  model_force_ = in.ReadDouble();
  ticks_ = in.ReadInt();
  virtual_->RestoreState(in);
  if (in.ReadBool() != (tick_ != nullptr))
    in.Fail(fmt::format("haptic probe '{}' is {} in this scene but was not in the checkpoint's",
                        name(), tick_ ? "coupled to an object" : "not coupled"));
  if (tick_) tick_->RestoreState(in);
}

void HapticCoupling::SaveConnectorState(StateWriter& out) const { bridge_->SaveState(out); }

void HapticCoupling::RestoreConnectorState(StateReader& in) { bridge_->RestoreState(in); }

}  // namespace gipsi
