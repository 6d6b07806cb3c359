/// @file
/// Connector checkpoints and snapshots: the base-class part (fire count) and the default hooks.

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/core/connector.h"

namespace gipsi {

void Connector::SaveState(StateWriter& out) const {
  out.BeginSection("Connector", 1);
  out.WriteString(name_);
  out.WriteString(type_name());
  out.WriteInt(fire_count_);
  out.BeginSection(type_name(), 1);
  SaveConnectorState(out);
  out.EndSection();
  out.EndSection();
}

void Connector::RestoreState(StateReader& in) {
  in.BeginSection("Connector", 1);
  const std::string name = in.ReadString();
  const std::string type = in.ReadString();
  if (name != name_ || type != type_name())
    in.Fail(fmt::format("the checkpoint has connector '{}' ({}) where this scene has '{}' ({})",
                        name, type, name_, type_name()));
  const std::int64_t fired = in.ReadInt();
  in.BeginSection(type_name(), 1);
  RestoreConnectorState(in);
  in.EndSection();
  in.EndSection();
  fire_count_ = fired;
}

namespace {

/// What Connector::TakeSnapshot copies: the fire count and the type's own state.
class ConnectorSnapshot final : public TypedState<ConnectorSnapshot> {
 public:
  ConnectorSnapshot(const Connector* connector, std::unique_ptr<ObjectState> own)
      : connector(connector), own(std::move(own)) {}

  void Assign(const ObjectState& other) override {
    const ConnectorSnapshot& o = Of(other);
    GIPSI_CHECK(o.connector == connector, "a snapshot of another connector");
    fire_count = o.fire_count;
    own->Assign(*o.own);
  }
  [[nodiscard]] std::string FirstDifference(const ObjectState& other) const override {
    const ConnectorSnapshot& o = Of(other);
    if (fire_count != o.fire_count) return "fire count";
    return own->FirstDifference(*o.own);
  }

  const Connector* connector;
  std::int64_t fire_count = 0;
  std::unique_ptr<ObjectState> own;
};

}  // namespace

std::unique_ptr<ObjectState> Connector::NewSnapshot() const {
  auto box = std::make_unique<ConnectorSnapshot>(this, NewConnectorState());
  TakeSnapshot(*box);
  return box;
}

void Connector::TakeSnapshot(ObjectState& into) const {
  ConnectorSnapshot& s = ConnectorSnapshot::Of(into);
  GIPSI_CHECK(s.connector == this, "connector '{}': a snapshot of another connector", name_);
  s.fire_count = fire_count_;
  CopyConnectorState(*s.own);
}

void Connector::RestoreSnapshot(const ObjectState& from) {
  const ConnectorSnapshot& s = ConnectorSnapshot::Of(from);
  GIPSI_CHECK(s.connector == this, "connector '{}': a snapshot of another connector", name_);
  fire_count_ = s.fire_count;
  SetConnectorState(*s.own);
}

Connector::~Connector() = default;

void Connector::BindStateBinding(std::unique_ptr<StateBinding> binding) {
  GIPSI_CHECK(state_binding_ == nullptr, "connector '{}': BindState called twice", name_);
  state_binding_ = std::move(binding);
}

void Connector::BindNoState() {
  static NoState nothing;  // has no fields: never read or written
  BindState(nothing);
}

std::unique_ptr<ObjectState> Connector::NewConnectorState() const {
  if (state_binding_) return state_binding_->New();
  return std::make_unique<ByteState>();
}

void Connector::CopyConnectorState(ObjectState& into) const {
  if (state_binding_) {
    state_binding_->Copy(into);
    return;
  }
  StateWriter out;
  out.BeginSection(type_name(), 1);
  SaveConnectorState(out);
  out.EndSection();
  ByteState::Of(into).bytes = out.TakeBytes();
}

void Connector::SetConnectorState(const ObjectState& from) {
  if (state_binding_) {
    state_binding_->Set(from);
    StateRestored();
    return;
  }
  StateReader in(ByteState::Of(from).bytes, fmt::format("the snapshot of connector '{}'", name_));
  in.BeginSection(type_name(), 1);
  RestoreConnectorState(in);
  in.EndSection();
}

void Connector::SaveConnectorState(StateWriter& out) const {
  if (state_binding_) {
    state_binding_->Write(out);
    return;
  }
  throw InputError(fmt::format("connector '{}': connector type {} does not support checkpoints",
                               name_, type_name()));
}

void Connector::RestoreConnectorState(StateReader& in) {
  if (state_binding_) {
    state_binding_->Read(in);
    StateRestored();
    return;
  }
  throw InputError(fmt::format("connector '{}': connector type {} does not support checkpoints",
                               name_, type_name()));
}

}  // namespace gipsi
