#pragma once
/// @file
/// Scene files: one JSON document describes a simulation (meshes, objects with their boundary
/// conditions, connectors, schedule with events, probes, outputs). The format is documented in
/// docs/scene-format.md. Every error names the file and the JSON path and says what was
/// expected.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/kernel.h"
#include "gipsi/core/registry.h"
#include "gipsi/io/boundary_condition_spec.h"
#include "gipsi/io/display_spec.h"
#include "gipsi/io/plot_spec.h"
#include "gipsi/io/probes.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// What to write as VTU/PVD series.
struct VtuOutputSpec {
  bool enabled = true;
  double every = 0;                  ///< seconds of simulated time; 0 = every macro step
  std::vector<std::string> objects;  ///< leaf object names; empty = all
  bool display = true;               ///< also write embedded display surfaces
};

/// Resource limits for running scenes from untrusted sources (`gipsi run --max-mesh-cells`,
/// `--max-output`). The defaults admit every scene we ship with a wide margin and stop a scene
/// that would exhaust the machine before anything large is allocated or written. Plain struct.
struct SceneLimits {
  /// Largest mesh of the scene's "meshes" (nodes, and tets + triangles), checked as each is
  /// built — before any object allocates per-element structures (which take many times the
  /// mesh's memory). The readers themselves never allocate beyond what the file holds.
  std::int64_t max_mesh_cells = 20'000'000;
  /// Largest total size [bytes] of the files a run may write (VTU/PVD series and probe CSVs),
  /// estimated from the scene before the run (EstimateOutputs in outputs.h); 0: no limit.
  std::uintmax_t max_output_bytes = 10'000'000'000;
};

/// A loaded, ready-to-run scene. Not copyable; movable.
struct Scene {
  std::filesystem::path file;
  std::unique_ptr<Kernel> kernel;
  double end_time = 0;
  std::filesystem::path output_directory;  ///< from the scene (relative to the working dir)
  std::vector<Probe> probes;
  VtuOutputSpec vtu;
  /// Plots to draw from the probe CSVs when a run ends ("outputs": {"plots": [...]}).
  std::vector<PlotSpec> plots;
  /// How objects are drawn (their "display" keys other than the embedded mesh): colour,
  /// geometry, wireframe, visibility. Objects without an entry are drawn in the default way.
  std::vector<std::pair<const SimObject*, DrawSpec>> display;
  std::map<std::string, std::shared_ptr<const Mesh>> meshes;
  /// Boundary conditions by "object/name", for events and `gipsi validate`.
  std::map<std::string, BoundaryConditionSpec> boundary_conditions;
  /// The limits it was loaded with (AttachOutputs checks the output volume against them).
  SceneLimits limits;
};

/// Largest scene file LoadScene reads [bytes]: 16 MiB (the shipped scenes take a few kB; meshes
/// live in their own files).
inline constexpr std::uintmax_t kMaxSceneFileBytes = 16u << 20;

/// Told as each stage of building a scene starts: what (e.g. "mesh 'box' (generate box)",
/// "object 'cube' (MassSpring)"), how many stages are done and how many there are.
using BuildProgressFn = std::function<void(std::string_view stage, int done, int total)>;

/// Loads `file` with the types in `registry` (loading the scene's plugins into it first) and
/// builds the kernel (Initialize is called). Throws InputError on any problem, including a mesh
/// over `limits.max_mesh_cells` and a file that is not a regular file of at most
/// kMaxSceneFileBytes. `progress`, if set, is told each build stage.
Scene LoadScene(const std::filesystem::path& file, TypeRegistry& registry,
                const SceneLimits& limits = {}, const BuildProgressFn& progress = {});
/// The same from text; `name` is used in messages and `base_dir` resolves relative paths.
Scene LoadSceneFromString(std::string_view text, const std::string& name,
                          const std::filesystem::path& base_dir, TypeRegistry& registry,
                          const SceneLimits& limits = {}, const BuildProgressFn& progress = {});

/// Where a scene's "plugins" entry points: a path with a '/' is taken relative to `base_dir`; a
/// bare name ("gipsi_example_plugin", ".so" optional) is searched in $GIPSI_PLUGIN_PATH
/// (colon-separated), then in `plugins/` and `lib/gipsi/plugins/` beside the executable's
/// folder, then in `base_dir`.
std::string ResolvePlugin(const std::string& entry, const std::filesystem::path& base_dir);

/// Builds a mesh from a scene "meshes" entry (file or generator, then scale/translate).
/// `base_dir` resolves relative file paths. Throws InputError.
Mesh BuildMesh(const JsonNode& node, const std::filesystem::path& base_dir);

}  // namespace gipsi
GIPSI_EXPORT_END
