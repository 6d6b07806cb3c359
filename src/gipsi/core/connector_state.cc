/// @file
/// Connector checkpoints: the base-class part (fire count) and the default hooks.

#include <fmt/format.h>

#include "gipsi/base/error.h"
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

void Connector::SaveConnectorState(StateWriter& /*out*/) const {
  throw InputError(fmt::format("connector '{}': connector type {} does not support checkpoints",
                               name_, type_name()));
}

void Connector::RestoreConnectorState(StateReader& /*in*/) {
  throw InputError(fmt::format("connector '{}': connector type {} does not support checkpoints",
                               name_, type_name()));
}

}  // namespace gipsi
