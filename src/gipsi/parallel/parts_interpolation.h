#pragma once
/// @file
/// PartitionedObject::InterpolateAtPoints for one rank's part (WholeDomainView's): values of a
/// split object's node field at points that each rank chooses for itself, each computed by the
/// rank whose part holds the point and sent to the rank that asked.
///
/// Set-up (collective, once): the parts' bounding boxes are gathered (6 numbers per rank); each
/// rank sends each of its points to the ranks whose box holds it, they locate it on their parts
/// (PointMap::BarycentricInTets) and answer how far it lies from them (0 inside, up to
/// rounding), and the point is taken from the nearest part, the lowest rank on a tie, as
/// LocateWhole does. A point that no part holds is asked again of every rank whose box is
/// nearer than the nearest part found, so a point outside the whole domain still goes to the
/// part nearest to it. The chosen rank keeps the point's weights. Each rank then holds O(its
/// points + the points it answers for others), and 6 numbers per rank for the boxes.
///
/// The nearest item (MakePartsNearest) goes the same way with each part's own items (each item
/// of the whole object on one rank only): round 0 asks the parts whose boxes hold the point and
/// the nearest box's, round 1 every other part whose box is no farther than the nearest item
/// found, and the nearest item is taken, the lowest whole index on a tie (as PointMap::Nearest
/// takes the lowest index).
///
/// On the boundary (MakePartsOnBoundary, for a boundary coupling) the candidates are each
/// part's boundary faces (each face of the whole boundary on one rank), asked in the same two
/// rounds as the nearest item; the point is projected onto the nearest face, and Spread sends
/// values at the points back the same way, each shared vertex's sum then to its node's owner.
///
/// Interpolate (collective, every firing): each rank reads its part's field, takes its shared
/// nodes' values from their owners, interpolates the points others asked of it and sends the
/// values back (MPI_Alltoallv with counts fixed at set-up; no allocation once the buffers have
/// grown to the field's width).

#include <mpi.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/parallel/mesh_partition.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// `part` is this rank's object on `mesh_part.mesh` (both must outlive the result); `points`
/// this rank's points; `part_field` turns the field ids Interpolate is given into the part's;
/// `share` sets a part node field's shared nodes to their owners' values
/// (PartitionedObject::ShareOwnedNodeValues). Collective; throws InputError on every rank if
/// any rank's point is not finite.
[[nodiscard]] std::unique_ptr<PartsInterpolation> MakePartsInterpolation(
    const SimObject& part, const MeshPart& mesh_part, const Points& points, MPI_Comm comm,
    std::function<FieldId(FieldId)> part_field,
    std::function<void(Eigen::Ref<Eigen::MatrixXd>)> share);

/// The items of a rank's part that a nearest-item copy may take: each item of the whole object
/// on exactly one rank. Plain struct.
struct NearestItems {
  Points positions;                ///< 3 × count rest positions
  std::vector<std::int64_t> keys;  ///< each item's index in the whole object
  std::vector<Index> columns;      ///< each item's column in the part's field
};

/// PartitionedObject::NearestAtPoints for one rank's part: `part`'s field values at `points`
/// (this rank's), each the value of the nearest of any rank's `items` (their rest positions;
/// the lowest key on a tie); `part_field` as above. Interpolate copies the item's value (a
/// no-data marker stays one). Collective; throws InputError on every rank if any rank's point is
/// not finite, or if there are points and no rank has items.
[[nodiscard]] std::unique_ptr<PartsInterpolation> MakePartsNearest(
    const SimObject& part, NearestItems items, const Points& points, MPI_Comm comm,
    std::function<FieldId(FieldId)> part_field);

/// PartitionedObject::InterpolateOnBoundary for one rank's part: `part`'s boundary-vertex fields
/// at `points` (this rank's), each interpolated on the nearest face of any rank's part boundary
/// (part.boundary(): the whole boundary's faces on the part's tets, each on one rank), and the
/// transpose (BoundaryInterpolation::Spread), whose shared vertices' sums go to the owner of
/// their node in `mesh_part` (`part`'s mesh part). `part_field` as above. Collective; throws
/// InputError on every rank if any rank's point is not finite, or if there are points and no
/// rank's part has a boundary face.
[[nodiscard]] std::unique_ptr<BoundaryInterpolation> MakePartsOnBoundary(
    const SimObject& part, const MeshPart& mesh_part, const Points& points, MPI_Comm comm,
    std::function<FieldId(FieldId)> part_field);

}  // namespace gipsi
GIPSI_EXPORT_END
