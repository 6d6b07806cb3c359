#pragma once
/// @file
/// OpenIGTLink in scene files:
///  - `ParseIgtlDevice`: the "device" block of a HapticProbe,
///    {"type": "OpenIGTLink", "host": "127.0.0.1", "port": 18944, "name": "Tool",
///     "length_unit": 0.001, "connect_timeout": 2, "reconnect_interval": 0.5}.
///  - `IgtlSurfaceSender` (connector "OpenIGTLinkSurface"): sends the deformed boundary surface
///    of an object through a probe's OpenIGTLink device as POLYDATA, at most `rate` times per
///    second of simulation time:
///    {"type": "OpenIGTLinkSurface", "object": "liver", "device": "probe", "rate": 30,
///     "name": "liver"}.

#include <string>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/core/connector.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/haptics/igtl_device.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Reads an OpenIGTLink device block (keys above; "type" must be "OpenIGTLink"). Throws
/// InputError naming the JSON path of an unknown key or a bad value.
IgtlDeviceParams ParseIgtlDevice(const JsonNode& node);

/// Not copyable or movable (a Connector).
class IgtlSurfaceSender final : public Connector {
 public:
  /// Sends `object`'s boundary surface through `device` as POLYDATA named `surface_name`, at
  /// most `rate` [Hz of simulation time] (> 0) times per second. Its port: it reads the
  /// object's "boundary_position" field (3 by boundary vertices, m). Throws InputError if the
  /// object has no boundary surface or no such field.
  IgtlSurfaceSender(std::string name, const SimObject& object, IgtlDevice& device, double rate,
                    std::string surface_name);
  [[nodiscard]] std::string_view type_name() const override { return "OpenIGTLinkSurface"; }
  /// Surfaces handed to the device so far.
  [[nodiscard]] std::int64_t num_queued() const { return queued_; }

 protected:
  /// Reads the boundary positions and queues them when a send is due. Allocation-free after
  /// the first firing on this side (the device copies into its own buffers).
  StepStatus DoFire(double t) override;

 private:
  const SimObject& object_;
  FieldId field_;  // the object's boundary_position
  IgtlDevice& device_;
  double period_;
  std::string surface_name_;
  double next_ = -1e300;
  Points positions_;
  std::int64_t queued_ = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
