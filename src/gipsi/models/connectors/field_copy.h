#pragma once
/// @file
/// `FieldCopy`: volume coupling by Get/Set. Reads a field of one object, maps it onto the items
/// of a field of another (which may live on a different mesh), scales it, and writes it.
///
/// Scene: {"type": "FieldCopy", "from": "a.field", "to": "b.field",
///         "mapping": "auto" | "direct" | "barycentric" | "nearest", "scale": 1.0}
/// Units: the target gets (source units) × (scale units). A plain-number scale is
/// dimensionless, so the two fields must have the same dimension; a scale with units
/// ("scale": "2 kPa/mV") carries the conversion. Fields declared in different units of that
/// dimension (ms and s) are converted.
/// "direct" needs equal item counts; "barycentric" interpolates node fields inside the source's
/// tets (or on its triangles); "nearest" takes the closest source item; "auto" picks direct when
/// the item positions coincide, barycentric for node fields, nearest otherwise.
/// A source field with a no-data marker (FieldInfo::no_data, e.g. `activation_time`'s -1) keeps
/// it apart: a target item whose value would read or blend the marker gets the target field's
/// marker (the source's if the target declares none), never a blend and never scaled.
/// Between objects split alike over the processes of a distributed run (SplitAlike), a direct or
/// barycentric copy runs part to part: each process reads its part of the source, takes the
/// values of the nodes it shares from their owners, and writes its part of the target; no
/// process gathers a whole field. A barycentric copy from a split object to one split
/// differently (another mesh, another cut) or whole asks the source's parts for the values at
/// the target's items, each process at its own (PartitionedObject::InterpolateAtPoints), and
/// one from a whole object onto a split one maps onto the target's part; no process gathers a
/// whole field either. A nearest-item copy goes the same way, each process asking the source's
/// parts for the nearest item to its own items (PartitionedObject::NearestAtPoints), except
/// from a boundary field of a split source that holds its whole domain (whole on every process).

#include <memory>
#include <optional>

#include "gipsi/base/export.h"
#include "gipsi/core/connector.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/core/registry.h"
#include "gipsi/geometry/mapping.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable or movable.
class FieldCopy final : public Connector {
 public:
  enum class Mapping { kAuto, kDirect, kBarycentric, kNearest };
  /// Resolves the mapping and buffers; throws InputError for incompatible fields (component
  /// counts differ, direct with different counts, a global field to a non-global one, units
  /// that do not give the target's: source units × `scale_units` must convert to the target's,
  /// an empty `scale_units` being dimensionless). Declares the ports (the source read, the
  /// target written, so the coordinator checks their access).
  FieldCopy(std::string name, SimObject& from, FieldId from_field, SimObject& to, FieldId to_field,
            Mapping mapping, double scale, const std::string& scale_units = {});

  [[nodiscard]] std::string_view type_name() const override { return "FieldCopy"; }
  /// The mapping in use (kDirect when values are copied item by item).
  [[nodiscard]] Mapping mapping() const { return mapping_; }
  /// The factor applied: the scale times the conversion of its units into the target's.
  [[nodiscard]] double factor() const { return scale_; }
  /// Whether it copies the objects' parts, process by process: split alike, or a barycentric
  /// or nearest copy from or onto a split object.
  [[nodiscard]] bool couples_parts() const override {
    return agree_on_ != nullptr || interpolation_ != nullptr;
  }

 protected:
  StepStatus DoFire(double t) override;

 private:
  // The objects read and written: the scene's, or their parts when they are split alike.
  const SimObject* from_;
  FieldId from_field_;
  SimObject* to_;
  FieldId to_field_;
  const PartitionedObject* split_ = nullptr;  // the split source, when copying parts alike
  // The split object whose part the target's values are for (they agree on a failure).
  const PartitionedObject* agree_on_ = nullptr;
  // A split source interpolated at the target's items by the parts that hold them.
  std::unique_ptr<PartsInterpolation> interpolation_;
  Mapping mapping_;
  double scale_;
  std::optional<PointMap> map_;
  Eigen::MatrixXd source_, target_;
};

void RegisterFieldCopy(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
