#pragma once
/// @file
/// Named fields: the values a simulation object lets others read (Get) and write (Set). This is
/// GiPSi's volume-coupling interface (e.g. excitation → active stress) and also how probes and
/// output writers see an object.

#include <optional>
#include <string>
#include <string_view>

#include "gipsi/base/export.h"
#include "gipsi/base/strong_id.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Where a field's items live; the item count follows from the object's geometries.
enum class FieldLocation {
  kNode,            ///< one item per domain node
  kElement,         ///< one item per domain element (tet, or triangle for surface domains)
  kBoundaryVertex,  ///< one item per boundary vertex
  kBoundaryFace,    ///< one item per boundary triangle
  kGlobal,          ///< one item for the whole object
};

/// Who may access a field from outside the object.
enum class FieldAccess { kRead, kWrite, kReadWrite };

/// Human-readable name of a location ("node", "element", ...).
std::string_view ToString(FieldLocation location);

struct FieldTag;
/// Index of a field within one object (stable after construction).
using FieldId = StrongId<FieldTag>;

/// Declaration of one field. Values are stored `components` by `count` (column j is item j):
/// 1 component for a scalar, 3 for a vector, 9 for a tensor (column-major 3×3).
struct FieldInfo {
  std::string name;  ///< e.g. "displacement"
  FieldLocation location = FieldLocation::kNode;
  int components = 1;  ///< 1, 3 or 9
  std::string units;   ///< SI unit string, e.g. "m", "N", "m/s", "1"
  FieldAccess access = FieldAccess::kRead;
  std::string description;  ///< one line for `gipsi validate` and the docs
  /// A value that marks an item without data (e.g. -1 for "never activated"). Probes neither
  /// interpolate nor reduce it: a point whose interpolation touches such an item reads this
  /// value, and region reductions skip such items (reading this value when all are such).
  std::optional<double> no_data = std::nullopt;

  [[nodiscard]] bool readable() const { return access != FieldAccess::kWrite; }
  [[nodiscard]] bool writable() const { return access != FieldAccess::kRead; }
};

}  // namespace gipsi
GIPSI_EXPORT_END
