#pragma once
/// @file
/// Probes: named points or regions whose field values are recorded over time to CSV.
///
///   "probes": {
///     "tip":  {"object": "sheet", "point": [x, y, z], "fields": ["displacement"], "every": 0.01},
///     "top":  {"object": "sheet", "region": <region>, "fields": ["reaction_force"],
///              "reduce": "sum"},
///     "energy": {"object": "sheet", "fields": ["kinetic_energy"]}
///   }
/// A point probe interpolates node fields at the point (barycentric in the domain at rest). A
/// region probe reduces node or boundary-vertex fields over the region ("mean", "sum", "min",
/// "max", per component). Global fields need neither. `every` is in seconds of simulated time
/// (default: every macro step).

#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gipsi/base/json_node.h"
#include "gipsi/core/kernel.h"
#include "gipsi/geometry/mapping.h"

namespace gipsi {

/// A probe resolved against the scene's objects. Copyable and movable.
struct Probe {
  enum class Reduce { kMean, kSum, kMin, kMax };
  std::string name;
  const SimObject* object = nullptr;
  std::vector<FieldId> fields;
  std::optional<PointMap> point;  ///< point probes: interpolation weights
  std::vector<int> items;         ///< region probes: node or boundary-vertex ids
  bool region = false;
  Reduce reduce = Reduce::kMean;
  double every = 0;

  /// CSV header: time then one column per component ("displacement_x", ...).
  [[nodiscard]] std::string Header() const;
  /// Current values, one per column after time.
  void Sample(std::vector<double>& out) const;
};

/// Parses and resolves one probe; throws InputError naming the JSON path (unknown object or
/// field, a point outside the domain, a region that selects nothing, an unsupported location).
Probe ParseProbe(const std::string& name, const JsonNode& node, const Kernel& kernel);

/// Records probes to `<directory>/<probe>.csv`, one row per sample, flushed as it goes so a run
/// that stops early keeps its rows.
class ProbeRecorder final : public Observer {
 public:
  /// Opens the files (throws std::runtime_error naming the file if one cannot be created).
  /// With `resume`, existing files are kept (RestoreState cuts them to the checkpoint's length).
  ProbeRecorder(std::vector<Probe> probes, const std::filesystem::path& directory,
                bool resume = false);
  void Observe(const Kernel& kernel, double t) override;
  void Finish(const Kernel& kernel) override;
  /// Checkpoints: next sample time and length of every file (defined in outputs.cc).
  void SaveState(StateWriter& out) override;
  void RestoreState(StateReader& in) override;

 private:
  struct Stream {
    Probe probe;
    std::ofstream file;
    double next = 0;
    std::filesystem::path path;
  };
  std::vector<Stream> streams_;
  std::vector<double> row_;
};

}  // namespace gipsi
