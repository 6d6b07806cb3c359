/// @file
/// The `gipsi` command-line tool: run, validate and inspect scenes and meshes; pace single
/// cardiac cells.
///
/// Exit codes: 0 success; 1 bad input (scene, mesh, plugin, cell model or parameter); 2 bad
/// command line; 3 the run stopped because an object diverged or failed; 4 writing outputs
/// failed; 130 interrupted.

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/base/state.h"
#include "gipsi/haptics/realtime_haptics.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/mesh_io.h"
#include "gipsi/io/mesh_summary.h"
#include "gipsi/io/outputs.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/ep/cell_models.h"
#include "gipsi/models/ep/single_cell.h"
#include "gipsi/viz/render/plot.h"
#include "viz_commands.h"

/// LeakSanitizer (sanitizer builds only; never called otherwise): libgmsh 4.8 leaks small
/// allocations while meshing (`meshGFace`, `discreteFace::_createGeometryFromSTL`) that
/// `gmsh::finalize` does not free. Scenes that generate meshes through Gmsh would otherwise make
/// the tool fail its leak check. The system graphics and plotting libraries (Mesa and its LLVM,
/// X11/GLX, GLFW, PLplot with libltdl, cairo, fontconfig and pango) keep one-time allocations they
/// never free either. Weak, so LSAN_OPTIONS suppressions still take precedence.
extern "C" __attribute__((weak)) const char* __lsan_default_suppressions() {
  return "leak:libgmsh.so\n"
         "leak:libOSMesa.so\nleak:libgallium\nleak:libLLVM\nleak:libglapi.so\n"
         "leak:_dri.so\nleak:libGLX_mesa.so\nleak:libGLdispatch.so\nleak:libX11.so\n"
         "leak:libxcb\nleak:libglfw.so\nleak:libplplot.so\nleak:libcairo.so\n"
         "leak:libfontconfig.so\nleak:libpango\nleak:libfreetype.so\nleak:libltdl.so\n";
}

namespace {

std::atomic<gipsi::Kernel*> g_running_kernel{nullptr};

extern "C" void HandleStopSignal(int) {
  if (gipsi::Kernel* kernel = g_running_kernel.load()) kernel->RequestStop();
}

/// Progress on a terminal: a bar rewritten in place at most 10 times a second; otherwise a plain
/// line at every 10 % of the run.
class Progress {
 public:
  explicit Progress(bool quiet) : quiet_(quiet), tty_(isatty(STDERR_FILENO) != 0) {}
  void Update(double t, double end) {
    if (quiet_ || end <= 0) return;
    const double fraction = std::min(1.0, t / end);
    auto now = std::chrono::steady_clock::now();
    if (tty_) {
      if (now - last_ < std::chrono::milliseconds(100) && fraction < 1.0) return;
      last_ = now;
      const int width = 30, filled = static_cast<int>(fraction * width);
      std::fprintf(stderr, "\r[%s%s] %5.1f%%  t = %.4g / %.4g s", std::string(filled, '#').c_str(),
                   std::string(width - filled, ' ').c_str(), 100 * fraction, t, end);
      std::fflush(stderr);
      dirty_ = true;
    } else {
      const int decile = static_cast<int>(fraction * 10 + 1e-9);
      if (decile <= last_decile_) return;
      last_decile_ = decile;
      std::fprintf(stderr, "progress: %3d%%  t = %.6g s\n", decile * 10, t);
    }
  }
  void Done() {
    if (dirty_) std::fprintf(stderr, "\n");
    dirty_ = false;
  }

 private:
  bool quiet_, tty_;
  bool dirty_ = false;
  int last_decile_ = 0;
  std::chrono::steady_clock::time_point last_{};
};

gipsi::Scene Load(const std::string& file, const std::vector<std::string>& plugins,
                  gipsi::TypeRegistry& registry, const gipsi::SceneLimits& limits) {
  gipsi::RegisterBuiltins(registry);
  for (const auto& plugin : plugins) registry.LoadPlugin(plugin);
  return gipsi::LoadScene(file, registry, limits);
}

/// Adds the resource-limit options (SceneLimits) to a subcommand.
void AddLimitOptions(CLI::App& command, gipsi::SceneLimits& limits) {
  command
      .add_option("--max-output", limits.max_output_bytes,
                  "Refuse to start a run whose outputs (VTU series, probe CSVs) are estimated "
                  "above SIZE, e.g. 500MB or 20GB; 0: no limit")
      ->transform(CLI::AsSizeValue(true))
      ->capture_default_str();
  command
      .add_option("--max-mesh-cells", limits.max_mesh_cells,
                  "Refuse a scene mesh with more nodes or cells (tets + triangles) than N")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

/// `gipsi run --profile`: where the wall time went, per object (with the object's own
/// breakdown), per connector, and in outputs.
std::string ProfileTable(const gipsi::Kernel& kernel, double wall_seconds) {
  const auto& coordinator = kernel.coordinator();
  auto share = [&](double s) { return wall_seconds > 0 ? 100.0 * s / wall_seconds : 0.0; };
  std::string table = "profile (wall time):\n";
  for (std::size_t i = 0; i < coordinator.num_objects(); ++i) {
    const auto& object = coordinator.object(i);
    const double s = coordinator.object_seconds(i);
    table += fmt::format("  object {:<20} {:>10.3f} s {:>5.1f} %\n", object.name(), s, share(s));
    for (const auto& entry : object.ProfileBreakdown()) {
      if (entry.unit == "s")
        table += fmt::format("    {:<27} {:>10.3f} s {:>5.1f} %\n", entry.name, entry.value,
                             share(entry.value));
      else
        table += fmt::format("    {:<27} {:>10.0f}\n", entry.name, entry.value);
    }
  }
  for (std::size_t i = 0; i < coordinator.num_connectors(); ++i) {
    const double s = coordinator.connector_seconds(i);
    table += fmt::format("  connector {:<17} {:>10.3f} s {:>5.1f} %\n",
                         coordinator.connector(i).name(), s, share(s));
  }
  table += fmt::format("  outputs (probes, VTU)       {:>10.3f} s {:>5.1f} %\n",
                       kernel.output_seconds(), share(kernel.output_seconds()));
  return table;
}

/// Options of `gipsi run` about checkpoints.
struct CheckpointOptions {
  double every = 0;    ///< simulated seconds between checkpoints; 0: none
  std::string file;    ///< where to write them (default <out>/checkpoint.gck)
  std::string resume;  ///< checkpoint to continue from
};

int Run(const std::string& file, const std::string& out_dir, double until, bool quiet, bool no_vtu,
        bool profile, const std::vector<std::string>& plugins, const CheckpointOptions& checkpoints,
        const gipsi::SceneLimits& limits) {
  gipsi::TypeRegistry registry;
  gipsi::Scene scene = Load(file, plugins, registry, limits);
  if (until > 0) scene.end_time = until;
  if (no_vtu) scene.vtu.enabled = false;
  std::filesystem::path out =
      out_dir.empty() ? scene.output_directory : std::filesystem::path(out_dir);
  gipsi::Kernel& kernel = *scene.kernel;
  // A real-time probe ticks on the wall clock: the run is not reproducible, so there is nothing
  // a checkpoint could restore bit for bit.
  if (checkpoints.every > 0 || !checkpoints.resume.empty())
    if (const auto probes = gipsi::RealtimeProbes(kernel); !probes.empty())
      gipsi::ThrowInputError(
          "command line", checkpoints.every > 0 ? "--checkpoint-every" : "--resume",
          fmt::format("the scene's HapticProbe '{}' is real-time (objects.{}.realtime): a "
                      "real-time run is not deterministic and cannot be checkpointed or resumed; "
                      "drop \"realtime\" for a reproducible run",
                      probes.front()->name(), probes.front()->name()));
  if (checkpoints.every > 0) {
    const double steps = checkpoints.every / kernel.macro_dt();
    const auto every = static_cast<std::int64_t>(std::llround(steps));
    if (every < 1 || std::abs(steps - static_cast<double>(every)) > 1e-9 * steps)
      gipsi::ThrowInputError("command line", "--checkpoint-every",
                             fmt::format("{} s is not a whole number of macro steps of {} s",
                                         checkpoints.every, kernel.macro_dt()));
    kernel.SetCheckpointing(
        checkpoints.file.empty() ? out / "checkpoint.gck" : std::filesystem::path(checkpoints.file),
        every);
    // Refuse now, not at the first checkpoint after minutes of running, if some object or
    // connector cannot save its state (a trial save into memory; no outputs exist yet).
    try {
      gipsi::StateWriter trial;
      kernel.SaveState(trial);
    } catch (const gipsi::InputError& e) {
      gipsi::ThrowInputError("command line", "--checkpoint-every",
                             fmt::format("this scene cannot be checkpointed: {}", e.what()));
    }
  }
  gipsi::AttachOutputs(scene, out, !checkpoints.resume.empty());
  if (!checkpoints.resume.empty()) kernel.ReadCheckpoint(checkpoints.resume);

  Progress progress(quiet);
  g_running_kernel.store(&kernel);
  std::signal(SIGINT, HandleStopSignal);
  std::signal(SIGTERM, HandleStopSignal);
  gipsi::RealtimeHaptics haptics(kernel);  // joins the loops however the run ends
  haptics.Start();
  gipsi::RunResult result =
      kernel.Run(scene.end_time, [&](double t, double end) { progress.Update(t, end); });
  haptics.Stop();  // logs each loop's period percentiles
  g_running_kernel.store(nullptr);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  progress.Done();

  std::string summary;
  summary += fmt::format("simulated time:   {:.6g} s (from {:.6g} s)\n",
                         result.end_time - result.start_time, result.start_time);
  summary += fmt::format("wall time:        {:.3f} s\n", result.wall_seconds);
  summary += fmt::format("real-time factor: {:.3g}\n", result.real_time_factor());
  summary +=
      fmt::format("macro steps:      {} of {:.6g} s\n", result.macro_steps, kernel.macro_dt());
  const auto& coordinator = kernel.coordinator();
  for (std::size_t i = 0; i < coordinator.num_objects(); ++i) {
    const auto& object = coordinator.object(i);
    summary += fmt::format("  {:<20} {:<14} {} steps of {:.6g} s\n", object.name(),
                           object.type_name(), object.step_count(), coordinator.object_dt(i));
  }
  for (std::size_t i = 0; i < coordinator.num_connectors(); ++i) {
    const auto& connector = coordinator.connector(i);
    summary += fmt::format("  {:<20} {:<14} fired {} times\n", connector.name(),
                           connector.type_name(), connector.fire_count());
  }
  for (const auto& [t, what] : kernel.fired_events())
    summary += fmt::format("  event at {:.6g} s: {}\n", t, what);
  if (kernel.retried_steps() > 0)
    summary +=
        fmt::format("retried steps:    {} (failed, rolled back, retried with halved steps)\n",
                    kernel.retried_steps());
  summary += fmt::format("outputs:          {}\n", out.string());
  std::string plot_error;  // plots of a run that stopped early still show what was recorded
  try {
    for (const auto& plot : gipsi::viz::WritePlots(scene.plots, out))
      summary += fmt::format("plot:             {}\n", plot.string());
  } catch (const std::exception& e) {
    plot_error = e.what();
  }
  if (profile) summary += ProfileTable(kernel, result.wall_seconds);
  if (!quiet || !result.ok() || profile) std::cout << summary << std::flush;

  if (!plot_error.empty() && result.ok()) {
    std::cerr << "gipsi: error: writing plots failed: " << plot_error << "\n";
    return 4;
  }
  switch (result.outcome) {
    case gipsi::RunResult::Outcome::kCompleted:
      return 0;
    case gipsi::RunResult::Outcome::kDiverged:
      std::cerr << "gipsi: error: " << result.diagnostic << "\n";
      return 3;
    case gipsi::RunResult::Outcome::kOutputFailed:
      std::cerr << "gipsi: error: " << result.diagnostic << "\n";
      return 4;
    case gipsi::RunResult::Outcome::kStopped:
      std::cerr << "gipsi: " << result.diagnostic << "\n";
      return 130;
  }
  return 0;
}

int Validate(const std::string& file, const std::vector<std::string>& plugins,
             const gipsi::SceneLimits& limits) {
  gipsi::TypeRegistry registry;
  gipsi::Scene scene = Load(file, plugins, registry, limits);
  const auto& coordinator = scene.kernel->coordinator();
  std::cout << fmt::format("{}: valid scene\n", file);
  std::cout << fmt::format("  end time {:.6g} s, macro step {:.6g} s\n", scene.end_time,
                           scene.kernel->macro_dt());
  for (const auto& [name, mesh] : scene.meshes)
    std::cout << fmt::format("  mesh {:<16} {} nodes, {} tets, {} triangles\n", name,
                             mesh->num_nodes(), mesh->num_tets(), mesh->num_triangles());
  for (std::size_t i = 0; i < coordinator.num_objects(); ++i) {
    const auto& object = coordinator.object(i);
    std::cout << fmt::format("  object {:<14} {} (dt {:.6g} s, {} sub-steps per macro step)\n",
                             object.name(), object.type_name(), coordinator.object_dt(i),
                             coordinator.object_substeps(i));
    for (const auto& field : object.fields())
      std::cout << fmt::format(
          "      field {:<22} {:<16} {}x [{}] {}\n", field.name, gipsi::ToString(field.location),
          field.components, field.units,
          field.writable() ? (field.readable() ? "read/write" : "write") : "read");
  }
  for (std::size_t i = 0; i < coordinator.num_connectors(); ++i)
    std::cout << fmt::format("  connector {:<11} {}\n", coordinator.connector(i).name(),
                             coordinator.connector(i).type_name());
  for (const auto& [key, bc] : scene.boundary_conditions)
    std::cout << fmt::format("  condition {:<22} {} vertices, {} faces\n", key, bc.vertices.size(),
                             bc.faces.size());
  for (const auto& probe : scene.probes)
    std::cout << fmt::format("  probe {:<15} {}\n", probe.name, probe.Header());
  const gipsi::OutputEstimate outputs = gipsi::EstimateOutputs(scene);
  std::cout << fmt::format(
      "  outputs: about {:.1f} MB ({} VTU frames, {:.1f} MB; probe CSVs at most {:.1f} MB)\n",
      static_cast<double>(outputs.total()) / 1e6, outputs.vtu_frames,
      static_cast<double>(outputs.vtu_bytes) / 1e6, static_cast<double>(outputs.probe_bytes) / 1e6);
  if (limits.max_output_bytes > 0 && outputs.total() > limits.max_output_bytes)
    std::cout << fmt::format(
        "  warning: over the output limit of {:.1f} MB (gipsi run refuses it)\n",
        static_cast<double>(limits.max_output_bytes) / 1e6);
  return 0;
}

int Info(const std::string& file) {
  gipsi::Mesh mesh = gipsi::ReadMesh(file);
  std::cout << file << "\n" << gipsi::DescribeMesh(mesh);
  return 0;
}

int Types(const std::vector<std::string>& plugins) {
  gipsi::TypeRegistry registry;
  gipsi::RegisterBuiltins(registry);
  for (const auto& plugin : plugins) registry.LoadPlugin(plugin);
  auto print = [](const char* title, const auto& list) {
    std::cout << title << ":\n";
    for (const auto& [name, description] : list)
      std::cout << fmt::format("  {:<18} {}\n", name, description);
  };
  print("objects", registry.objects.List());
  print("connectors", registry.connectors.List());
  print("integrators", registry.integrators.List());
  print("material laws", registry.materials.List());
  print("cell models", registry.cell_models.List());
  print("haptic local models (by object type)", registry.local_models.List());
  return 0;
}

/// Options of `gipsi cell`.
struct CellOptions {
  std::string model;
  std::string variant;
  std::vector<std::string> params;  // key=value (value parsed as JSON, else taken as a string)
  gipsi::PacingProtocol protocol;
  std::optional<double> stim_amplitude, stim_duration;
  std::string out;
  std::int64_t every = 10;
};

/// The model's JSON description from the command line: {"model": MODEL, "variant": ..., k: v}.
nlohmann::ordered_json CellSpec(const CellOptions& options) {
  nlohmann::ordered_json spec = {{"model", options.model}};
  if (!options.variant.empty()) spec["variant"] = options.variant;
  for (const auto& param : options.params) {
    const auto eq = param.find('=');
    if (eq == std::string::npos || eq == 0)
      gipsi::ThrowInputError("command line", "--param",
                             fmt::format("expected key=value, got '{}'", param));
    const std::string key = param.substr(0, eq), value = param.substr(eq + 1);
    nlohmann::ordered_json parsed = nlohmann::ordered_json::parse(value, nullptr, false);
    spec[key] = parsed.is_discarded() ? nlohmann::ordered_json(value) : parsed;
  }
  return spec;
}

int Cell(CellOptions options, const std::vector<std::string>& plugins) {
  gipsi::TypeRegistry registry;
  gipsi::RegisterBuiltins(registry);
  for (const auto& plugin : plugins) registry.LoadPlugin(plugin);
  const nlohmann::ordered_json spec = CellSpec(options);
  auto model = gipsi::CreateCellModel(registry, gipsi::JsonNode(spec, "command line", "cell"));
  gipsi::PacingProtocol& protocol = options.protocol;
  protocol.stim_amplitude = options.stim_amplitude.value_or(model->default_stimulus().amplitude);
  protocol.stim_duration = options.stim_duration.value_or(model->default_stimulus().duration);
  protocol.record_every = 0;

  std::ofstream csv;
  gipsi::CellSampleFn sink;
  if (!options.out.empty()) {
    csv.open(options.out);
    if (!csv) {
      std::cerr << "gipsi: error: cannot create " << options.out << "\n";
      return 4;
    }
    csv << gipsi::CellTraceCsvHeader(*model) << '\n';
    std::string row;
    sink = [&csv, row](double t, std::span<const double> state) mutable {
      row = fmt::format("{:.10g}", t);
      for (double x : state) row += fmt::format(",{:.10g}", x);
      row += '\n';
      csv << row;
    };
  }
  const gipsi::SingleCellResult result =
      gipsi::PaceSingleCell(*model, protocol, {}, sink, options.out.empty() ? 0 : options.every);

  std::string variant(model->variant());
  std::cout << fmt::format("model:    {}{}, {} states; {}\n", model->type_name(),
                           variant.empty() ? "" : " (" + variant + ")", model->num_states(),
                           model->scheme());
  std::cout << fmt::format(
      "pacing:   {} beats at bcl {:g} ms, dt {:g} ms, stimulus {:g} uA/uF for {:g} ms\n",
      protocol.beats, protocol.bcl, protocol.dt, protocol.stim_amplitude, protocol.stim_duration);
  const std::string apd = fmt::format("APD{:g}", protocol.apd_percent);
  std::cout << fmt::format("{:>5} {:>10} {:>9} {:>9} {:>10} {:>10} {:>9}\n", "beat", "start_ms",
                           "rest_mV", "peak_mV", "dVdt_max", "act_ms", apd + "_ms");
  for (const auto& b : result.beats)
    std::cout << fmt::format("{:>5} {:>10.6g} {:>9.3f} {:>9.3f} {:>10.2f} {:>10.3f} {:>9.2f}\n",
                             b.beat, b.start, b.rest, b.peak, b.dvdt_max, b.activation, b.apd);
  if (!options.out.empty()) {
    csv.flush();
    if (!csv) {
      std::cerr << "gipsi: error: writing " << options.out << " failed\n";
      return 4;
    }
    std::cout << "trace:    " << options.out << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"GiPSi: an open-architecture framework for organ-level and surgical simulation"};
  app.set_version_flag("--version", "gipsi 0.1.0");
  app.require_subcommand(1);
  std::string scene_file, out_dir, mesh_file;
  double until = 0;
  bool quiet = false, no_vtu = false, verbose = false, profile = false;
  std::vector<std::string> plugins;
  app.add_flag("-v,--verbose", verbose, "Log more (debug level)");

  auto* run =
      app.add_subcommand("run", "Run a scene headless, writing VTU/PVD series and probe CSVs");
  run->add_option("SCENE", scene_file, "Scene file (JSON)")->required();
  run->add_option("-o,--out", out_dir, "Output directory (default: the scene's, or out/<scene>)");
  run->add_option("--until", until, "End time in seconds, overriding schedule.end")
      ->check(CLI::PositiveNumber);
  run->add_flag("-q,--quiet", quiet,
                "No progress bar, no summary unless the run fails, and only warnings and errors "
                "in the log");
  run->add_flag("--no-vtu", no_vtu, "Do not write VTU/PVD series (probes are still written)");
  run->add_flag("--profile", profile,
                "Print where the wall time went: per object (and its own breakdown, e.g. "
                "assembly and linear solves), per connector, and in outputs");
  run->add_option("--plugin", plugins, "Load a plugin shared library (repeatable)");
  gipsi::SceneLimits limits;
  AddLimitOptions(*run, limits);
  CheckpointOptions checkpoints;
  run->add_option("--checkpoint-every", checkpoints.every,
                  "Write a checkpoint every T seconds of simulated time (a whole number of macro "
                  "steps), and when stopped by SIGINT/SIGTERM")
      ->check(CLI::PositiveNumber);
  run->add_option("--checkpoint", checkpoints.file,
                  "Checkpoint file to write (default: <out>/checkpoint.gck)");
  run->add_option("--resume", checkpoints.resume,
                  "Continue from a checkpoint of the same scene, appending to the outputs in the "
                  "output directory (continued outputs are bitwise identical to an "
                  "uninterrupted run with the same thread count)");

  auto* validate = app.add_subcommand("validate", "Check a scene without running it");
  validate->add_option("SCENE", scene_file, "Scene file (JSON)")->required();
  validate->add_option("--plugin", plugins, "Load a plugin shared library (repeatable)");
  AddLimitOptions(*validate, limits);

  auto* info = app.add_subcommand(
      "info", "Describe a mesh file: counts, named regions, bounding box, element quality");
  info->add_option("MESH", mesh_file, "Mesh file (.msh, .node/.ele, .vtk, .vtu, .obj, .stl)")
      ->required();

  auto* types = app.add_subcommand(
      "types", "List the registered object, connector, integrator and material types");
  types->add_option("--plugin", plugins, "Load a plugin shared library (repeatable)");

  CellOptions cell_options;
  auto* cell = app.add_subcommand(
      "cell", "Pace a single cell of a cardiac cell model; print per-beat biomarkers");
  cell->add_option("MODEL", cell_options.model,
                   "Cell model (AlievPanfilov, MitchellSchaeffer, FitzHughNagumo, Nagumo, "
                   "TenTusscherPanfilov2006)")
      ->required();
  cell->add_option("--variant", cell_options.variant, "Model variant (TTP06: epi, endo, M)");
  cell->add_option("--param", cell_options.params,
                   "Model parameter key=value, e.g. g_ks=0.2 (repeatable)");
  cell->add_option("--bcl", cell_options.protocol.bcl, "Basic cycle length [ms]")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cell->add_option("--beats", cell_options.protocol.beats, "Number of beats")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cell->add_option("--dt", cell_options.protocol.dt, "Time step [ms]")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cell->add_option("--stim-amplitude", cell_options.stim_amplitude,
                   "Stimulus [uA/uF], positive depolarises (default: the model's)");
  cell->add_option("--stim-duration", cell_options.stim_duration,
                   "Stimulus duration [ms] (default: the model's)")
      ->check(CLI::NonNegativeNumber);
  cell->add_option("--apd", cell_options.protocol.apd_percent,
                   "Repolarisation level of the APD [%]")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  cell->add_option("--threshold", cell_options.protocol.activation_threshold,
                   "Activation threshold [mV]")
      ->capture_default_str();
  cell->add_option("-o,--out", cell_options.out,
                   "Write a CSV trace: t_ms then every state variable");
  cell->add_option("--every", cell_options.every, "Write every K-th step to the CSV")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cell->add_option("--plugin", plugins, "Load a plugin shared library (repeatable)");

  gipsi::apps::VizCommands viz_commands(app);

  CLI11_PARSE(app, argc, argv);
  // -q (run): warnings and errors only; -v: debug lines too.
  gipsi::Log().set_level(quiet     ? spdlog::level::warn
                         : verbose ? spdlog::level::debug
                                   : spdlog::level::info);
  try {
    if (*run)
      return Run(scene_file, out_dir, until, quiet, no_vtu, profile, plugins, checkpoints, limits);
    if (*validate) return Validate(scene_file, plugins, limits);
    if (*info) return Info(mesh_file);
    if (*types) return Types(plugins);
    if (*cell) return Cell(cell_options, plugins);
    if (auto code = viz_commands.Dispatch()) return *code;
  } catch (const gipsi::InputError& e) {
    std::cerr << "gipsi: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "gipsi: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
