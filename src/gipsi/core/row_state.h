#pragma once
/// @file
/// `RowState`: capability of an object whose state is rows of values per item of its domain
/// (nodes, tets, boundary faces) plus values that do not depend on the items (a clock, a solver
/// count), so that the state can move between objects of the same type on other items: a split
/// object's part restored on another partition, a checkpoint resumed on another rank count
/// (gipsi/parallel/whole_domain_view.h, docs/scale-out.md). The rows are read from and written
/// in the type's own checkpoint format (SaveObjectState's bytes), so nothing else changes.
/// DistributedMonodomain and FemSolid have it.

#include <cstdint>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/state.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// How many items of each kind an object's domain has. Plain struct.
struct ItemCounts {
  std::int64_t nodes = 0, tets = 0, faces = 0;  ///< faces: of the boundary
};

/// A state as rows: each kind's rows item after item (width values each, 0: none of that kind),
/// and the rest as bytes that are the same for every part of one object. Plain struct.
struct StateRows {
  int node_width = 0, tet_width = 0, face_width = 0;
  std::vector<double> node, tet, face;
  std::string shared;
};

/// Interface, implemented beside SimObject; asked for with dynamic_cast. Not copyable.
class RowState {
 public:
  RowState() = default;
  RowState(const RowState&) = delete;
  RowState& operator=(const RowState&) = delete;
  virtual ~RowState() = default;

  /// Reads the type's state as SaveObjectState wrote it for an object of this type and
  /// configuration whose domain had `counts` items (another part's), as rows. Solver caches
  /// that hold nothing but the bits of a continuation (a kept factorisation) are skipped.
  /// Throws InputError for data of another layout.
  [[nodiscard]] virtual StateRows ReadStateRows(StateReader& in,
                                                const ItemCounts& counts) const = 0;
  /// Writes the type's state in SaveObjectState's format for this object, from rows of its own
  /// items (in its order) and the shared bytes (with empty solver caches). Throws InputError if
  /// the widths or the shared bytes do not fit this object.
  virtual void WriteStateRows(StateWriter& out, const StateRows& rows) const = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
