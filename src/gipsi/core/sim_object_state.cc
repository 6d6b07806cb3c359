/// @file
/// SimObject checkpoints and snapshots: the base-class part (clock, step count, applied boundary
/// conditions) and the default hooks (the type's state serialised, for types without a state
/// value type).

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/core/sim_object.h"

namespace gipsi {

namespace {

// SaveState's layout: the header, the applied boundary conditions, the type's state.
void WriteSaved(StateWriter& out, std::string_view name, std::string_view type, double time,
                std::int64_t steps, const BoundaryConditions& bcs,
                const std::function<void(StateWriter&)>& write_own) {
  out.BeginSection("SimObject", 2);
  out.WriteString(name);
  out.WriteString(type);
  out.WriteDouble(time);
  out.WriteInt(steps);
  bcs.SaveApplied(out);  // the coupling loads are not state: the next macro step clears them
  out.BeginSection(type, 1);
  write_own(out);
  out.EndSection();
  out.EndSection();
}

}  // namespace

void SimObject::SaveState(StateWriter& out) const {
  WriteSaved(out, name_, type_name(), time_, step_count_, bcs_,
             [this](StateWriter& w) { SaveObjectState(w); });
}

void SimObject::RestoreState(StateReader& in) {
  in.BeginSection("SimObject", 2);
  const std::string name = in.ReadString();
  const std::string type = in.ReadString();
  if (name != name_ || type != type_name())
    in.Fail(fmt::format("the checkpoint has object '{}' ({}) where this scene has '{}' ({})", name,
                        type, name_, type_name()));
  const double time = in.ReadDouble();
  const std::int64_t steps = in.ReadInt();
  RestoreAppliedConditions(in);
  in.BeginSection(type_name(), 1);
  RestoreObjectState(in);
  in.EndSection();
  in.EndSection();
  time_ = time;
  step_count_ = steps;
}

void SimObject::RestoreAppliedConditions(StateReader& in) { bcs_.RestoreApplied(in); }

SimObject::SavedHeader SimObject::ReadSavedState(
    StateReader& in, Index boundary_vertices, Index boundary_faces,
    const std::function<void(StateReader&)>& read_own) {
  SavedHeader header;
  in.BeginSection("SimObject", 2);
  header.name = in.ReadString();
  header.type = in.ReadString();
  header.time = in.ReadDouble();
  header.steps = in.ReadInt();
  BoundaryConditions(boundary_vertices, boundary_faces).RestoreApplied(in);
  in.BeginSection(header.type, 1);
  read_own(in);
  in.EndSection();
  in.EndSection();
  return header;
}

void SimObject::RestoreStateFrom(double time, std::int64_t steps,
                                 const std::function<void(StateWriter&)>& write_own) {
  StateWriter out;
  WriteSaved(out, name_, type_name(), time, steps, bcs_, write_own);
  StateReader in(out.TakeBytes(), fmt::format("object '{}' moved to this partition", name_));
  RestoreState(in);
}

namespace {

/// What SimObject::TakeSnapshot copies: the clock, the step count, the applied boundary
/// conditions (only when their stamp changed) and the type's own state.
class SimObjectSnapshot final : public TypedState<SimObjectSnapshot> {
 public:
  SimObjectSnapshot(const SimObject* object, std::unique_ptr<ObjectState> own)
      : object(object), own(std::move(own)) {}

  void Assign(const ObjectState& other) override {
    const SimObjectSnapshot& o = Of(other);
    GIPSI_CHECK(o.object == object, "a snapshot of another object");
    time = o.time;
    steps = o.steps;
    if (bcs.stamp != o.bcs.stamp) bcs = o.bcs;
    own->Assign(*o.own);
  }
  [[nodiscard]] std::string FirstDifference(const ObjectState& other) const override {
    const SimObjectSnapshot& o = Of(other);
    if (!state_detail::SameBits(&time, &o.time, 1)) return "time";
    if (steps != o.steps) return "step count";
    std::string d = gipsi::FirstDifference(bcs, o.bcs);
    if (!d.empty()) return "boundary conditions: " + d;
    return own->FirstDifference(*o.own);
  }

  const SimObject* object;
  double time = 0;
  std::int64_t steps = 0;
  BoundaryConditions::Applied bcs;
  std::unique_ptr<ObjectState> own;
};

}  // namespace

std::unique_ptr<ObjectState> SimObject::NewSnapshot() const {
  auto box = std::make_unique<SimObjectSnapshot>(this, NewObjectState());
  TakeSnapshot(*box);
  return box;
}

void SimObject::TakeSnapshot(ObjectState& into) const {
  SimObjectSnapshot& s = SimObjectSnapshot::Of(into);
  GIPSI_CHECK(s.object == this, "object '{}': a snapshot of another object", name_);
  s.time = time_;
  s.steps = step_count_;
  if (s.bcs.stamp != bcs_.applied().stamp) s.bcs = bcs_.applied();
  CopyObjectState(*s.own);
}

void SimObject::RestoreSnapshot(const ObjectState& from) {
  const SimObjectSnapshot& s = SimObjectSnapshot::Of(from);
  GIPSI_CHECK(s.object == this, "object '{}': a snapshot of another object", name_);
  time_ = s.time;
  step_count_ = s.steps;
  bcs_.SetApplied(s.bcs);
  SetObjectState(*s.own);
}

std::unique_ptr<ObjectState> SimObject::NewObjectState() const {
  if (state_binding_) return state_binding_->New();
  return std::make_unique<ByteState>();
}

void SimObject::CopyObjectState(ObjectState& into) const {
  if (state_binding_) {
    state_binding_->Copy(into);
    return;
  }
  StateWriter out;
  out.BeginSection(type_name(), 1);
  SaveObjectState(out);
  out.EndSection();
  ByteState::Of(into).bytes = out.TakeBytes();
}

void SimObject::SetObjectState(const ObjectState& from) {
  if (state_binding_) {
    state_binding_->Set(from);
    DropStateCache();
    StateRestored();
    return;
  }
  StateReader in(ByteState::Of(from).bytes, fmt::format("the snapshot of object '{}'", name_));
  in.BeginSection(type_name(), 1);
  RestoreObjectState(in);
  in.EndSection();
}

void SimObject::SaveObjectState(StateWriter& out) const {
  if (state_binding_) {
    state_binding_->Write(out);
    SaveStateCache(out);
    return;
  }
  throw InputError(
      fmt::format("object '{}': object type {} does not support checkpoints", name_, type_name()));
}

void SimObject::RestoreObjectState(StateReader& in) {
  if (state_binding_) {
    state_binding_->Read(in, [this](StateReader& r) { RestoreStateCache(r); });
    StateRestored();
    return;
  }
  throw InputError(
      fmt::format("object '{}': object type {} does not support checkpoints", name_, type_name()));
}

}  // namespace gipsi
