#pragma once
/// @file
/// `NodeStatePart`: a split object's part (WholeDomainView's) whose state is one row of values
/// per mesh node plus values every part holds alike, so that a checkpoint written on one rank
/// count can be restored on another: each file's part is read as rows of its nodes (whatever
/// their number), the rows go to the ranks whose new parts hold those nodes (MoveNodeRows), and
/// each part writes itself back from its rows in its own layout (docs/scale-out.md,
/// Checkpoints). DistributedMonodomain is one; a type that is not cannot change rank count.

#include <cstdint>
#include <span>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/state.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// An interface (the part also derives from SimObject). Not copyable.
class NodeStatePart {
 public:
  NodeStatePart() = default;
  NodeStatePart(const NodeStatePart&) = delete;
  NodeStatePart& operator=(const NodeStatePart&) = delete;
  virtual ~NodeStatePart() = default;

  /// Values in a node's row.
  [[nodiscard]] virtual int node_row_width() const = 0;
  /// Reads the type's state as SaveObjectState wrote it for a part of this type with
  /// `num_nodes` local nodes (another partition's): a row per node, node after node, into
  /// `rows`, and the values that are the same on every part into `shared`. Throws InputError
  /// for data of another layout.
  virtual void ReadNodeRows(StateReader& in, std::int64_t num_nodes, std::vector<double>& rows,
                            std::vector<double>& shared) const = 0;
  /// Writes the type's state in SaveObjectState's format for this part, from `rows` of its
  /// local nodes (in local order) and `shared`.
  virtual void WriteNodeRows(StateWriter& out, std::span<const double> rows,
                             std::span<const double> shared) const = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
