#pragma once
/// @file
/// `PartitionedObject`: capability of an object split over the processes of a distributed run
/// (gipsi/parallel/) that may hold only its own part of the domain. Such an object's domain()
/// is then this process's part (local node numbering), and what needs the whole domain goes
/// through the collective calls below, on the whole domain's node indices, which every process
/// knows without holding the whole mesh. Probes use them (io/probes.h; region probes reduce
/// through them on whole objects too, so no process gathers a region); other consumers of the
/// object's fields (connectors, events) are not offered such an object: the scene loader gives
/// an object its whole domain when anything else in the scene names it
/// (ObjectBuildContext::standalone).
///
/// Every process must make the same calls in the same order (they do when every process runs
/// the same kernel on the same scene).

#include <cstdint>
#include <span>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/core/field.h"
#include "gipsi/geometry/mapping.h"
#include "gipsi/geometry/region.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

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
  /// ReadFieldItems of a node field at local nodes (from SelectOwnedNodes). Not collective.
  virtual void ReadOwnedNodes(FieldId id, std::span<const int> local,
                              Eigen::Ref<Eigen::MatrixXd> out) const = 0;
  /// How CombineAcross combines.
  enum class Combine { kSum, kMin, kMax };
  /// Replaces every entry of `values` by its sum, minimum or maximum over the processes.
  /// Collective: O(values.size()) per process.
  virtual void CombineAcross(std::span<double> values, Combine how) const = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
