#pragma once
/// @file
/// Probes: named points or regions whose field values are recorded over time to CSV.
///
///   "probes": {
///     "tip":  {"object": "sheet", "point": [x, y, z], "fields": ["displacement"], "every": 0.01},
///     "top":  {"object": "sheet", "region": <region>, "fields": ["reaction_force"],
///              "reduce": "sum"},
///     "energy": {"object": "sheet", "fields": ["kinetic_energy"]},
///     "diagonal": {"object": "tissue", "line": {"from": [0, 0, 0], "to": [0.02, 0.007, 0.003],
///                  "points": 101}, "fields": ["activation_time"], "at": [0.03, 0.06]}
///   }
/// A point probe interpolates node fields at the point (barycentric in the domain at rest). A
/// region probe reduces node or boundary-vertex fields over the region ("mean", "sum", "min",
/// "max", per component). Global fields need neither. `every` is in seconds of simulated time
/// (default: every macro step). A field's no-data marker (FieldInfo::no_data) is never blended:
/// a point touching a marked item reads the marker, and reductions skip marked items.
///
/// A line probe samples node fields at `points` evenly spaced points from `from` to `to`
/// (interpolated like a point probe, through SimObject::MapFromNodes) at the times `at` [s] (at
/// the first macro step reaching each), or once at the end of the run when `at` is absent. Its
/// CSV has one row per point and sample time: time, distance along the line from `from`, the
/// point's x, y, z (rest coordinates), then the field columns.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/core/kernel.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/geometry/mapping.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A probe resolved against the scene's objects. Copyable and movable.
struct Probe {
  enum class Reduce { kMean, kSum, kMin, kMax };
  std::string name;
  const SimObject* object = nullptr;
  std::vector<FieldId> fields;
  /// Point and line probes: interpolation weights, over the columns of `items` (the nodes the
  /// points need, sorted): a sample reads those items only (SimObject::ReadFieldItems).
  std::optional<PointMap> point;
  /// Point and line probes on node fields: the node ids of `point`'s slots, for the object's
  /// correction of the blend (SimObject::CorrectInterpolated).
  Eigen::Matrix4Xi nodes = Eigen::Matrix4Xi(4, 0);
  /// Line probes: the sample points (3 by n, rest coordinates) and distances from the first.
  Points line = Points(3, 0);
  std::vector<double> distance;
  /// Line probes: sample times [s], ascending; empty = once, at the end of the run.
  std::vector<double> at;
  std::vector<int> items;  ///< node or boundary-vertex ids read by each sample
  /// Set when the object holds only its part of the domain (a distributed run's object without
  /// its whole mesh): `items` and `point`'s nodes are then whole-domain node ids, read through it.
  const PartitionedObject* partitioned = nullptr;
  /// Region probes of node or boundary-vertex fields on an object split over the processes
  /// (with or without its whole mesh): `items` are then the local nodes (boundary vertices) this
  /// process owns in the region, reduced here and combined across the processes through it (no
  /// process gathers the region).
  const PartitionedObject* owners = nullptr;
  bool region = false;
  Reduce reduce = Reduce::kMean;
  double every = 0;

  [[nodiscard]] bool is_line() const { return line.cols() > 0; }
  /// CSV header: time then one column per component ("displacement_x", ...); line probes have
  /// "distance,x,y,z" after time.
  [[nodiscard]] std::string Header() const;
  /// Current values, one per column after time (line probes: all rows, row after row, each
  /// starting with distance, x, y, z).
  void Sample(std::vector<double>& out) const;

 private:
  // The values of field `id` at `items` (through `partitioned` when set).
  void ReadItems(FieldId id, Eigen::MatrixXd& values) const;
};

/// Parses and resolves one probe; throws InputError naming the JSON path (unknown object or
/// field, a point outside the domain, a region that selects nothing, an unsupported location).
Probe ParseProbe(const std::string& name, const JsonNode& node, const Kernel& kernel);

/// Records probes to `<directory>/<probe>.csv`, one row per sample, flushed as it goes so a run
/// that stops early keeps its rows.
class ProbeRecorder final : public Observer {
 public:
  /// Opens the files (throws std::runtime_error naming the file if one cannot be created).
  /// With `resume`, the files are neither created nor opened here: RestoreState checks them
  /// against the checkpoint, CommitRestore cuts them to the checkpoint's length and opens them.
  /// With `read_only` (the ranks of a distributed run but the first, outputs.h) it samples
  /// every probe at the same times and creates or writes no file.
  ProbeRecorder(std::vector<Probe> probes, const std::filesystem::path& directory,
                bool resume = false, bool read_only = false);
  void Observe(const Kernel& kernel, double t) override;
  void Finish(const Kernel& kernel) override;
  /// Checkpoints: next sample time and length of every file (defined in outputs.cc).
  void SaveState(StateWriter& out) override;
  void RestoreState(StateReader& in) override;
  void CommitRestore() override;

 private:
  struct Stream {
    Probe probe;
    std::ofstream file;
    double next = 0;
    std::size_t next_at = 0;  // line probes: index into probe.at
    std::filesystem::path path;
    std::uintmax_t resume_length = 0;  // the file's length at the checkpoint being restored
  };
  void Write(Stream& s, double t);
  std::vector<Stream> streams_;
  std::vector<double> row_;
  bool write_ = true;
};

}  // namespace gipsi
GIPSI_EXPORT_END
