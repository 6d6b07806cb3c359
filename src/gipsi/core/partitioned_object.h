#pragma once
/// @file
/// `PartitionedObject`: capability of an object split over the processes of a distributed run
/// (gipsi/parallel/) that may hold only its own part of the domain. Such an object's domain()
/// is then this process's part (local node numbering), and what needs the whole domain goes
/// through the collective calls below, on the whole domain's node indices, which every process
/// knows without holding the whole mesh. Probes use them (io/probes.h; region probes reduce
/// through them on whole objects too, so no process gathers a region), and so do connectors that
/// couple parts (below; Connector::couples_parts). Other consumers of the object's fields (other
/// connectors, events) are not offered such an object: the scene loader gives an object its
/// whole domain when anything else in the scene names it (ObjectBuildContext::in_blocks), and
/// Coordinator::Prepare refuses any other connector's use of its node or element fields.
///
/// Two split objects cut differently (on two meshes, a fine one for the bioelectricity and a
/// coarse one for the mechanics) are coupled through InterpolateAtPoints (or NearestAtPoints
/// for a nearest-item copy): each process asks the source's parts for the values at its own
/// target items, and the parts that hold them answer.
///
/// Two split objects cut alike (SplitAlike: the same whole domain, the same part on every
/// process) can be coupled part to part: a connector reads one's local_part() and writes the
/// other's, each process its own share, and refreshes the nodes its part shares with other
/// processes from their owners (ShareOwnedNodeValues: O(the part's surface)) instead of gathering
/// whole fields.
///
/// Every process must make the same calls in the same order (they do when every process runs
/// the same kernel on the same scene).

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/core/field.h"
#include "gipsi/geometry/mapping.h"
#include "gipsi/geometry/region.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class SimObject;

/// Values of a split object's node field at points that each process chooses for itself (its
/// own part's items, or anything else): made by PartitionedObject::InterpolateAtPoints, for a
/// connector between objects split differently (another mesh, another cut). Each point is
/// interpolated by the process whose part holds it and sent to the process that asked, so no
/// process gathers the field. Not copyable.
class PartsInterpolation {
 public:
  PartsInterpolation() = default;
  PartsInterpolation(const PartsInterpolation&) = delete;
  PartsInterpolation& operator=(const PartsInterpolation&) = delete;
  virtual ~PartsInterpolation() = default;
  /// This process's points.
  [[nodiscard]] virtual Index num_points() const = 0;
  /// The farthest any process's point lies from the whole domain (0 inside; a point outside
  /// takes the nearest point of the domain, as MapFromNodes does), the same on every process.
  [[nodiscard]] virtual double max_distance() const = 0;
  /// The object's node field `id` at this process's points, into `out` (components ×
  /// num_points()): barycentric in the whole domain's tet that holds the point (on several
  /// parts, the lowest process's; outside, the nearest part's), from the nodes' owners' values,
  /// with the object's own higher-order correction (SimObject::CorrectInterpolated). With
  /// `no_data` (the field's marker), a point whose tet has a node holding the marker gets the
  /// marker, as PointMap::ApplyMarked. Collective: each process sends the values others asked
  /// of its part and the values its part's shared nodes take from their owners.
  virtual void Interpolate(FieldId id, Eigen::Ref<Eigen::MatrixXd> out,
                           std::optional<double> no_data) const = 0;
};

/// A PartsInterpolation on a split object's boundary (PartitionedObject::InterpolateOnBoundary,
/// for a boundary coupling of parts): the object's boundary-vertex fields at points each process
/// gives, each interpolated on the whole boundary's face nearest to the point (barycentric on
/// the face, the point projected onto it: PointMap::BarycentricOnTriangles) by the process whose
/// part holds that face (the lowest such process on a tie), and the transpose of that
/// interpolation, which spreads values at the points back onto the faces' vertices. Not
/// copyable.
class BoundaryInterpolation : public PartsInterpolation {
 public:
  /// How far each of this process's points lies from the whole boundary (from the nearest point
  /// of its nearest face), the same for a point whichever process asks.
  [[nodiscard]] virtual std::span<const double> distances() const = 0;
  /// Interpolate (above) reads a boundary-vertex field, with no higher-order correction.
  /// Spread is its transpose: each of this process's points' values (`at_points`, 3 ×
  /// num_points()) weighted as Interpolate weighs the vertices of the point's face, summed over
  /// every process's points into `out` (3 × the vertices of the part's boundary,
  /// SimObject::boundary()): on each vertex this process owns (its node's owner) the whole sum,
  /// zero on the others, so that a force spread so counts once (a part counts a nodal force on
  /// its node's owner only). The sums are made in a fixed order: bitwise the same on the same
  /// processes. Collective: the values go back to the processes that answered, then the shared
  /// vertices' sums to their owners (O(the points + the part's shared boundary vertices)).
  virtual void Spread(const Eigen::Ref<const Eigen::MatrixXd>& at_points,
                      Eigen::Ref<Eigen::MatrixXd> out) const = 0;
};

/// Interface, implemented beside SimObject; asked for with dynamic_cast.
class PartitionedObject {
 public:
  virtual ~PartitionedObject() = default;
  /// False when domain() is this process's part only: then probes must use the calls below.
  [[nodiscard]] virtual bool holds_whole_domain() const = 0;
  /// The whole domain's bounding-box diagonal. Collective.
  [[nodiscard]] virtual double WholeDiagonal() const = 0;
  /// The whole domain's node and tet counts (output estimates).
  [[nodiscard]] virtual std::int64_t whole_num_nodes() const = 0;
  [[nodiscard]] virtual std::int64_t whole_num_tets() const = 0;
  /// MapFromNodes on the whole domain: interpolation weights at `targets` over whole-domain node
  /// indices, the same on every process; a point on several processes' parts is taken from the
  /// lowest of them, one outside the domain from the part nearest to it (max_distance() as
  /// MapFromNodes). Collective.
  [[nodiscard]] virtual PointMap LocateWhole(const Points& targets) const = 0;
  /// SelectNodes on the whole domain: the whole-domain indices of the nodes in `region`,
  /// sorted, the same on every process (node ids in `region` are whole-domain indices).
  /// Collective; throws InputError on every process as SelectNodes does.
  [[nodiscard]] virtual std::vector<int> SelectWholeNodes(const Region& region) const = 0;
  /// ReadFieldItems of a node field at whole-domain node indices (each valid, from LocateWhole
  /// or SelectWholeNodes), each value from the process that owns the node, on every process.
  /// Collective: O(items) sent and received per process.
  virtual void ReadWholeNodes(FieldId id, std::span<const int> nodes,
                              Eigen::Ref<Eigen::MatrixXd> out) const = 0;

  // Reductions over a region without moving its values: each process reduces the nodes it
  // owns, then the partial results are combined (region probes; whole or part-only objects).
  /// The local indices of the nodes this process owns among SelectWholeNodes(region): every
  /// node of the whole domain's selection on exactly one process. A group region's nodes are
  /// gathered (a triangle or tet group names a node only where its triangle or tet is); other
  /// regions are decided where the nodes are, with no communication. Collective; throws
  /// InputError on every process as SelectNodes does.
  [[nodiscard]] virtual std::vector<int> SelectOwnedNodes(const Region& region) const = 0;
  /// ReadFieldItems of a node field at local nodes (from SelectOwnedNodes), or of a
  /// boundary-vertex field at local boundary vertices (SelectOwnedBoundaryVertices). Not
  /// collective.
  virtual void ReadOwnedNodes(FieldId id, std::span<const int> local,
                              Eigen::Ref<Eigen::MatrixXd> out) const = 0;
  /// How CombineAcross combines.
  enum class Combine { kSum, kMin, kMax };
  /// Replaces every entry of `values` by its sum, minimum or maximum over the processes.
  /// Collective: O(values.size()) per process.
  virtual void CombineAcross(std::span<double> values, Combine how) const = 0;
  /// The local indices of the vertices of this process's part of the whole boundary whose node
  /// it owns among SelectWholeNodes(region): every vertex of the whole selection on exactly one
  /// process, whether or not the object also holds its whole domain. Region probes of
  /// boundary-vertex fields reduce them as SelectOwnedNodes' nodes (ReadOwnedNodes reads them).
  /// Only on an object with boundary-vertex fields. Collective.
  [[nodiscard]] virtual std::vector<int> SelectOwnedBoundaryVertices(
      const Region& region) const = 0;

  // Boundary conditions on an object without its whole domain (holds_whole_domain() false).
  /// Where a condition on `region` goes in the object's store of boundary conditions, which
  /// holds its part's boundary only (boundary_conditions(): the vertices and triangles of
  /// domain()'s boundary, in their order). Plain struct.
  struct ConditionItems {
    std::vector<int> items;        ///< this process's selected vertices (or triangles), sorted
    std::int64_t whole_count = 0;  ///< how many the whole boundary's selection has
  };
  /// The part's boundary vertices, or with `faces` its triangles, that `region` selects as
  /// SelectBoundaryVertices and SelectBoundaryFaces select them on the whole domain, and the
  /// size of the whole selection (a vertex counted once over the processes, though every part
  /// holding it selects it: the part counts a nodal force on its node's owner only). No process
  /// holds more than its part's. Collective; throws InputError on every process as SelectNodes
  /// does, or if the object takes no boundary conditions.
  [[nodiscard]] virtual ConditionItems SelectConditionItems(const Region& region,
                                                            bool faces) const = 0;

  // Coupling part to part (SplitAlike).
  /// This process's part: the object that steps this process's share of the domain. Its node
  /// and element fields are per local node and tet; local nodes [0, num_owned_nodes()) are the
  /// ones this process owns, the others are shared with (and owned by) other processes.
  [[nodiscard]] virtual SimObject& local_part() = 0;
  [[nodiscard]] virtual const SimObject& local_part() const = 0;
  [[nodiscard]] virtual Index num_owned_nodes() const = 0;
  /// The whole domain's index of each node and each tet of local_part()'s domain, in its order.
  [[nodiscard]] virtual std::span<const int> whole_nodes_of_part() const = 0;
  [[nodiscard]] virtual std::span<const int> whole_tets_of_part() const = 0;
  /// Sets the columns of `values` (components × local_part()'s nodes) at the shared nodes to
  /// those their owners hold. Collective: each process sends the owned nodes other processes
  /// share and receives its shared ones (O(the part's surface); neighbours only).
  virtual void ShareOwnedNodeValues(Eigen::Ref<Eigen::MatrixXd> values) const = 0;

  // Coupling objects split differently (another mesh, another cut).
  /// Interpolation of this object's node fields at `points`, which each process gives for
  /// itself (any number, none included; a split target's own items): see PartsInterpolation.
  /// Each point is located on the parts whose bounding boxes hold it (and, when it lies outside
  /// every part, on the parts that might be nearer); a process then holds O(its points + the
  /// points it interpolates for others). Collective; throws InputError on every process if a
  /// point is not finite.
  [[nodiscard]] virtual std::unique_ptr<PartsInterpolation> InterpolateAtPoints(
      const Points& points) const = 0;
  /// Values of this object's fields at `location` (node, element, or on an object without its
  /// whole domain boundary vertex or face) at `points`, which each process gives for itself,
  /// each the value of the whole object's item nearest to the point by rest position (the
  /// lowest index on a tie, as PointMap::Nearest), sent by the process that holds the item.
  /// PartsInterpolation::Interpolate copies the item's value, with no correction (a no-data
  /// marker stays one); its max_distance() is the farthest any point lies from its item.
  /// Collective; throws InputError on every process if a point is not finite or if there are
  /// points and the object has no such items, and for a boundary location on an object that
  /// holds its whole domain (whose boundary fields are whole on every process).
  [[nodiscard]] virtual std::unique_ptr<PartsInterpolation> NearestAtPoints(
      FieldLocation location, const Points& points) const = 0;
  /// On an object without its whole domain (holds_whole_domain() false): interpolation of its
  /// boundary-vertex fields at `points` on its whole boundary, and the transpose (see
  /// BoundaryInterpolation), each process giving its own points. Each point is asked of the
  /// parts whose boundary's box holds it and of the nearest box's, then of every other part
  /// whose box is no farther than the nearest face found. Collective; throws InputError on
  /// every process if a point is not finite, if there are points and the whole boundary has no
  /// faces, or on an object that holds its whole domain (its boundary fields are whole on every
  /// process: interpolate them there).
  [[nodiscard]] virtual std::unique_ptr<BoundaryInterpolation> InterpolateOnBoundary(
      const Points& points) const = 0;
  /// This process's number among the object's processes (0 to num_processes() - 1), and their
  /// count: for a connector that splits work on a whole end among them.
  [[nodiscard]] virtual int process() const = 0;
  [[nodiscard]] virtual int num_processes() const = 0;
};

/// True when `a` and `b` are both PartitionedObjects split alike: on every process their parts
/// hold the same whole-domain nodes, at the same rest positions, and the same whole-domain tets,
/// in the same order (two objects on one mesh cut by the same partitioner on the same processes).
/// A node or element index of one part is then the same item of the other's. Collective over the
/// processes of `a` when both are split (an agreement: the same answer on every process); false
/// at once, on every process alike, when either is not split.
[[nodiscard]] bool SplitAlike(const SimObject& a, const SimObject& b);

/// An item whose value is not finite, and the value. Plain struct.
struct NonFiniteItem {
  Index item = 0;
  double value = 0;
};
/// The first item (column) of `values` with a non-finite entry, or nullopt. With `split` (a
/// coupling of parts: `values` per local node or tet of its part, as `location` says), the
/// smallest whole-domain index of any process's first such item, the same on every process so
/// that all stop alike, with a NaN value (each process sees only its own). Collective then.
[[nodiscard]] std::optional<NonFiniteItem> FirstNonFinite(
    const Eigen::Ref<const Eigen::MatrixXd>& values, FieldLocation location,
    const PartitionedObject* split);

}  // namespace gipsi
GIPSI_EXPORT_END
