#include "gipsi/haptics/igtl_surface_sender.h"

#include <fmt/format.h>

#include "gipsi/base/build_info.h"
#include "gipsi/base/error.h"

namespace gipsi {

IgtlDeviceParams ParseIgtlDevice(const JsonNode& node) {
  if (!node.is_object()) node.Expected("an object {\"type\": \"OpenIGTLink\", \"host\": ...}");
  node.CheckKeys(
      {"type", "host", "port", "name", "length_unit", "connect_timeout", "reconnect_interval"});
  (void)node.At("type").AsChoice({"OpenIGTLink", "Mouse"});
  if (!GetBuildFeatures().openigtlink)
    node.Fail(MissingFeature("an OpenIGTLink device", "OpenIGTLink", "GIPSI_WITH_OPENIGTLINK"));
  IgtlDeviceParams p;
  p.host = node.String("host", p.host);
  if (p.host.empty()) node.At("host").Expected("a host name or address");
  const std::int64_t port = node.Int("port", p.port);
  if (port < 1 || port > 65535) node.At("port").Expected("a TCP port in 1-65535");
  p.port = static_cast<int>(port);
  p.device_name = node.String("name", p.device_name);
  if (p.device_name.empty()) node.At("name").Expected("a non-empty OpenIGTLink device name");
  p.length_unit = node.Positive("length_unit", p.length_unit);
  p.connect_timeout = node.Positive("connect_timeout", p.connect_timeout);
  if (p.connect_timeout > 60) node.At("connect_timeout").Expected("at most 60 s");
  p.reconnect_interval = node.Positive("reconnect_interval", p.reconnect_interval);
  return p;
}

IgtlSurfaceSender::IgtlSurfaceSender(std::string name, const SimObject& object, IgtlDevice& device,
                                     double rate, std::string surface_name)
    : Connector(std::move(name)),
      object_(object),
      field_(object.FindField("boundary_position")),
      device_(device),
      period_(1.0 / rate),
      surface_name_(std::move(surface_name)) {
  GIPSI_CHECK(rate > 0, "IgtlSurfaceSender: rate must be positive");
  if (object.boundary().num_vertices() == 0)
    throw InputError(fmt::format("object '{}' has no boundary surface", object.path()));
  UseField("object", object, "boundary_position", FieldAccess::kRead, "m", 3);
  positions_.resize(3, object.boundary().num_vertices());
}

StepStatus IgtlSurfaceSender::DoFire(double t) {
  // A relative tolerance of 1e-9 absorbs rounding of accumulated times, so a rate equal to the
  // firing rate sends at every firing.
  if (t + 1e-9 * period_ < next_) return StepStatus::Ok();
  next_ = next_ + period_ > t ? next_ + period_ : t + period_;
  object_.ReadField(field_, positions_);
  device_.SendSurface(positions_, object_.boundary().triangles, surface_name_);
  ++queued_;
  return StepStatus::Ok();
}

}  // namespace gipsi
