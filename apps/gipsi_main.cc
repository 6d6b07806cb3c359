/// @file
/// The `gipsi` command-line tool: run, validate and inspect scenes and meshes; pace single
/// cardiac cells.
///
/// Exit codes: 0 success; 1 bad input (scene, mesh, plugin, cell model or parameter); 2 bad
/// command line; 3 the run stopped because an object diverged or failed; 4 writing outputs
/// failed; 130 interrupted.

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <mutex>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <CLI/CLI.hpp>

#include "cli_checks.h"
#include "gipsi/base/build_info.h"
#include "gipsi/base/error.h"
#include "gipsi/base/file_io.h"
#include "gipsi/base/log.h"
#include "gipsi/base/state.h"
#include "gipsi/base/version.h"
#include "gipsi/core/aggregate.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/row_state.h"
#include "gipsi/haptics/realtime_haptics.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/mesh_io.h"
#include "gipsi/io/mesh_summary.h"
#include "gipsi/io/outputs.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/ep/cell_models.h"
#include "gipsi/models/ep/single_cell.h"
#include "gipsi/numerics/simd.h"
#include "gipsi/parallel/distributed_run.h"
#include "gipsi/viz/render/plot.h"
#include "run_progress.h"
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

/// AddressSanitizer's defaults (sanitizer builds only; never called otherwise). Debian 12's
/// libfreeimage, loaded through Gmsh's OpenCASCADE (libTKService), frees at exit with free() a
/// block it allocated with operator new(nothrow); clang's ASan reports that alloc-dealloc
/// mismatch and aborts every program as it exits. Not GiPSi's allocation, and ASan 14 cannot
/// suppress that report per library, so the mismatch check is off (GiPSi allocates through
/// containers and smart pointers). Weak, so ASAN_OPTIONS still take precedence.
extern "C" __attribute__((weak)) const char* __asan_default_options() {
  return "alloc_dealloc_mismatch=0";
}

namespace {

std::atomic<gipsi::Kernel*> g_running_kernel{nullptr};

/// SIGINT/SIGTERM: a running kernel stops after its current macro step (Kernel::RequestStop,
/// also when the request comes before its Run starts), flushing its outputs. Before there is a
/// kernel — while the scene and its meshes are built, which writes nothing — the tool exits
/// at once with 130.
extern "C" void HandleStopSignal(int) {
  if (gipsi::Kernel* kernel = g_running_kernel.load()) {
    kernel->RequestStop();
    return;
  }
  constexpr char kMessage[] = "\ngipsi: stopped on request while building the scene\n";
  [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, kMessage, sizeof(kMessage) - 1);
  std::_Exit(130);
}

/// Installs HandleStopSignal for SIGINT and SIGTERM while alive; restores the defaults after.
class StopSignals {
 public:
  StopSignals() {
    std::signal(SIGINT, HandleStopSignal);
    std::signal(SIGTERM, HandleStopSignal);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  ~StopSignals() {
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
  }
};

/// Makes `kernel` the one a stop signal asks to stop, while alive (declare it after the kernel's
/// owner, so it is gone before the kernel is).
class SignalTarget {
 public:
  explicit SignalTarget(gipsi::Kernel& kernel) { g_running_kernel.store(&kernel); }
  SignalTarget(const SignalTarget&) = delete;
  SignalTarget& operator=(const SignalTarget&) = delete;
  ~SignalTarget() { g_running_kernel.store(nullptr); }
};

/// Progress of building a scene (gipsi::BuildProgressFn): which stage (mesh, object, ...) is
/// being built and for how long, from a thread that looks every 100 ms. On a terminal a line
/// rewritten in place once the build has taken 0.5 s; otherwise a plain line for each stage that
/// takes over 2 s, when it has taken 2 s and when it ends. Nothing with -q.
class BuildProgress {
 public:
  explicit BuildProgress(bool quiet) : quiet_(quiet), tty_(isatty(STDERR_FILENO) != 0) {
    if (quiet_) return;
    start_ = stage_start_ = std::chrono::steady_clock::now();
    ticker_ = std::thread([this] { Tick(); });
  }
  BuildProgress(const BuildProgress&) = delete;
  BuildProgress& operator=(const BuildProgress&) = delete;
  ~BuildProgress() { Done(); }

  /// The callback for LoadScene.
  gipsi::BuildProgressFn Callback() {
    if (quiet_) return {};
    return [this](std::string_view stage, int done, int total) {
      std::lock_guard lock(mutex_);
      EndStage();
      stage_ = fmt::format("[{}/{}] {}", done + 1, total, stage);
      stage_start_ = std::chrono::steady_clock::now();
    };
  }

  /// Stops the ticker and clears the line (idempotent).
  void Done() {
    if (quiet_) return;
    {
      std::lock_guard lock(mutex_);
      if (finished_) return;
      finished_ = true;
      EndStage();
      if (drawn_) std::fprintf(stderr, "\r\033[K");
      std::fflush(stderr);
    }
    wake_.notify_all();
    ticker_.join();
  }

 private:
  using Clock = std::chrono::steady_clock;
  static double Seconds(Clock::time_point since) {
    return std::chrono::duration<double>(Clock::now() - since).count();
  }
  void EndStage() {  // mutex_ held
    if (announced_)
      std::fprintf(stderr, "building: %s: done in %.1f s\n", stage_.c_str(), Seconds(stage_start_));
    announced_ = false;
  }
  void Tick() {
    std::unique_lock lock(mutex_);
    while (!wake_.wait_for(lock, std::chrono::milliseconds(100), [this] { return finished_; })) {
      if (stage_.empty()) continue;
      if (tty_) {
        if (Seconds(start_) < 0.5) continue;
        std::fprintf(stderr, "\rbuilding %s  %.1f s (total %.1f s)\033[K", stage_.c_str(),
                     Seconds(stage_start_), Seconds(start_));
        drawn_ = true;
      } else if (!announced_ && Seconds(stage_start_) > 2.0) {
        std::fprintf(stderr, "building: %s ...\n", stage_.c_str());
        announced_ = true;
      }
      std::fflush(stderr);
    }
  }

  bool quiet_, tty_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread ticker_;
  std::string stage_;
  Clock::time_point start_, stage_start_;
  bool finished_ = false, drawn_ = false, announced_ = false;
};

/// The ranks of a distributed run (`mpirun -np N gipsi run`; docs/scale-out.md): every rank
/// loads and runs the same scene, the distributed types split their objects over the ranks,
/// and rank 0 alone writes files and prints. One rank (size 1) is a serial run.
struct Ranks {
  int rank = 0;
  int size = 1;
  /// Replaces the registry's factories of the distributed types (empty for a serial run).
  std::function<void(gipsi::TypeRegistry&)> register_types;
  /// Ends every rank with `code` (a rank that stops alone would leave the others waiting).
  std::function<void(int)> abort;
  std::function<void()> barrier;
  /// DistributedRun::SetCheckpointFiles.
  std::function<void(std::vector<std::filesystem::path>)> set_checkpoint_files;
  /// DistributedRun::AgreeOnFailure.
  std::function<std::optional<std::string>(const std::string&)> agree_on_failure;
  /// The objects split over the ranks, as "name (Type)" (once the scene is loaded).
  std::function<std::vector<std::string>()> split_objects;
  [[nodiscard]] bool distributed() const { return size > 1; }
};

/// Loads the scene with its build progress (unless `quiet`).
gipsi::Scene Load(const std::string& file, const std::vector<std::string>& plugins,
                  gipsi::TypeRegistry& registry, const gipsi::SceneLimits& limits, bool quiet,
                  const Ranks& ranks = {}) {
  gipsi::RegisterBuiltins(registry);
  for (const auto& plugin : plugins) registry.LoadPlugin(gipsi::ResolvePlugin(plugin, "."));
  if (ranks.register_types) ranks.register_types(registry);
  BuildProgress progress(quiet);
  return gipsi::LoadScene(file, registry, limits, progress.Callback());
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
      ->check(gipsi::apps::IntegerIn(1, INT64_MAX, "a positive whole number"))
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
        table += fmt::format("    {:<27} {:>10.0f}{}\n", entry.name, entry.value,
                             entry.unit.empty() ? "" : " " + entry.unit);
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

/// The VTU frames of `series` under `out` that GiPSi wrote: `<series>/<series>_NNNNNN.vtu`.
std::vector<std::filesystem::path> FrameFiles(const std::filesystem::path& out,
                                              const std::string& series) {
  std::vector<std::filesystem::path> frames;
  std::error_code error;
  const std::filesystem::path dir = out / series;
  if (!std::filesystem::is_directory(dir, error)) return frames;
  auto digits = [](std::string_view text) {
    return !text.empty() &&
           std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
  };
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    const std::string name = entry.path().filename().string();
    const std::string prefix = series + "_";
    if (!entry.is_regular_file(error) || !name.starts_with(prefix) ||
        name.size() < prefix.size() + 6 + 4 || !digits(name.substr(prefix.size(), 6)))
      continue;
    // <series>_NNNNNN.vtu, or a distributed run's <series>_NNNNNN.pvtu and _NNNNNN_p<rank>.vtu.
    const std::string_view rest = std::string_view(name).substr(prefix.size() + 6);
    const bool piece =
        rest.starts_with("_p") && rest.ends_with(".vtu") && digits(rest.substr(2, rest.size() - 6));
    if (rest == ".vtu" || rest == ".pvtu" || piece) frames.push_back(entry.path());
  }
  return frames;
}

/// Before a fresh (not resumed) run writes VTU series into `out`: a series of the same name
/// from an earlier run there would keep frames the new, perhaps shorter, run's `.pvd` no longer
/// lists. Refuses (InputError naming the directory) unless `overwrite`; with it, deletes the
/// earlier series' frames and collections — only files of the form GiPSi writes
/// (`<out>/<series>.pvd`, `<out>/<series>/<series>_NNNNNN.vtu`, and a distributed run's
/// `_NNNNNN.pvtu` and `_NNNNNN_p<rank>.vtu`), nothing else.
void PrepareOutputDirectory(const gipsi::Scene& scene, const std::filesystem::path& out,
                            bool resume, bool overwrite) {
  if (resume || !scene.vtu.enabled) return;
  std::vector<const gipsi::SimObject*> leaves;
  const auto& coordinator = scene.kernel->coordinator();
  if (scene.vtu.objects.empty()) {
    for (std::size_t i = 0; i < coordinator.num_objects(); ++i)
      coordinator.object(i).CollectLeaves(leaves);
  } else {
    for (const auto& name : scene.vtu.objects) scene.kernel->FindObject(name).CollectLeaves(leaves);
  }
  std::vector<std::filesystem::path> stale;
  std::string first;
  for (const gipsi::SimObject* leaf : leaves) {
    for (const std::string& series : {leaf->name(), leaf->name() + "_display"}) {
      std::vector<std::filesystem::path> frames = FrameFiles(out, series);
      std::error_code error;
      const std::filesystem::path pvd = out / (series + ".pvd");
      if (std::filesystem::is_regular_file(pvd, error)) frames.push_back(pvd);
      if (!frames.empty() && first.empty())
        first = fmt::format("{} ({} files)", series, frames.size());
      stale.insert(stale.end(), frames.begin(), frames.end());
    }
  }
  if (stale.empty()) return;
  if (!overwrite)
    gipsi::ThrowInputError(
        "command line", "--out",
        fmt::format("{} holds VTU series of an earlier run (e.g. {}); a new run would leave "
                    "frames its .pvd does not list: choose another --out, or add --overwrite to "
                    "delete the earlier series there first",
                    out.string(), first));
  for (const auto& file : stale) {
    std::error_code error;
    std::filesystem::remove(file, error);
    if (error)
      throw gipsi::OutputError(
          fmt::format("{}: cannot delete the earlier output: {}", file.string(), error.message()));
  }
  gipsi::Log().info("--overwrite: deleted {} files of earlier VTU series in {}", stale.size(),
                    out.string());
}

/// A distributed run's checkpoint `file` as each rank writes it: `<stem>_p<rank><extension>`
/// (checkpoint.gck: checkpoint_p0.gck, checkpoint_p1.gck, ...; docs/scale-out.md).
std::filesystem::path RankFile(const std::filesystem::path& file, int rank) {
  std::filesystem::path name = file.stem();
  name += fmt::format("_p{}", rank);
  name += file.extension();
  return file.parent_path() / name;
}

/// Before a resume: the files of a distributed checkpoint (`<stem>_p0`, `_p1`, ... that exist),
/// which a distributed run reads whatever its rank count (rank q reads rank q % N's file of N,
/// and split objects read the others' parts, docs/scale-out.md), also for a run on one process
/// (which reads rank 0's file, its serial objects taking every rank's part of a split one), or
/// a serial run's one file, which every rank of a distributed run reads (split objects take
/// their parts of it). A missing file is left to the reader.
std::vector<std::filesystem::path> CheckResumeFiles(const std::filesystem::path& resume,
                                                    const Ranks& ranks) {
  std::error_code error;
  std::vector<std::filesystem::path> pieces;  // the files _p0, _p1, ... that exist
  while (std::filesystem::exists(RankFile(resume, static_cast<int>(pieces.size())), error))
    pieces.push_back(RankFile(resume, static_cast<int>(pieces.size())));
  if (ranks.distributed()) {
    // Every rank looks at the same files and refuses alike (a rank whose file exists would
    // otherwise wait for the others).
    if (!pieces.empty()) return pieces;
    if (std::filesystem::is_regular_file(resume, error)) return {resume};  // a serial run's
    return {RankFile(resume, ranks.rank)};  // missing: the reader says so
  }
  if (std::filesystem::exists(resume, error)) return {};
  return pieces;  // a distributed run's: the serial objects take the split ones' parts
}

/// Options of `gipsi run` about checkpoints.
struct CheckpointOptions {
  double every = 0;    ///< simulated seconds between checkpoints; 0: none
  std::string file;    ///< where to write them (default <out>/checkpoint.gck)
  std::string resume;  ///< checkpoint to continue from
};

int Run(const std::string& file, const std::string& out_dir, double until, bool quiet, bool no_vtu,
        bool profile, bool overwrite, const std::vector<std::string>& plugins,
        const CheckpointOptions& checkpoints, const gipsi::SceneLimits& limits,
        const Ranks& ranks = {}) {
  StopSignals signals;  // while building: exit 130 at once; then: stop the run cleanly
  std::vector<std::filesystem::path> resume_files;  // a distributed checkpoint's, rank 0's first
  if (!checkpoints.resume.empty()) resume_files = CheckResumeFiles(checkpoints.resume, ranks);
  const bool lead = ranks.rank == 0;  // writes files and prints
  if (!lead) quiet = true;
  gipsi::TypeRegistry registry;
  gipsi::Scene scene = Load(file, plugins, registry, limits, quiet, ranks);
  if (until > 0) scene.end_time = until;
  if (no_vtu) scene.vtu.enabled = false;
  std::filesystem::path out =
      out_dir.empty() ? scene.output_directory : std::filesystem::path(out_dir);
  gipsi::Kernel& kernel = *scene.kernel;
  // From here a signal asks the kernel to stop (it does after at most one macro step of Run).
  const SignalTarget signal_target(kernel);
  // A real-time probe ticks on the wall clock: the run is not reproducible, so there is nothing
  // a checkpoint could restore bit for bit.
  if (checkpoints.every > 0 || !checkpoints.resume.empty())
    if (const auto probes = gipsi::RealtimeProbes(kernel); !probes.empty())
      gipsi::ThrowInputError(
          "command line", checkpoints.every > 0 ? "--checkpoint-every" : "--resume",
          fmt::format("the scene's HapticProbe '{}' is real-time (objects.{}.realtime): a "
                      "real-time run is not deterministic and cannot be checkpointed or resumed; "
                      "drop \"realtime\" for a reproducible run",
                      probes.front().object->name(), probes.front().object->name()));
  if (checkpoints.every > 0) {
    const double steps = checkpoints.every / kernel.macro_dt();
    const auto every = static_cast<std::int64_t>(std::llround(steps));
    if (every < 1 || std::abs(steps - static_cast<double>(every)) > 1e-9 * steps)
      gipsi::ThrowInputError("command line", "--checkpoint-every",
                             fmt::format("{} s is not a whole number of macro steps of {} s",
                                         checkpoints.every, kernel.macro_dt()));
    const std::filesystem::path file =
        checkpoints.file.empty() ? out / "checkpoint.gck" : std::filesystem::path(checkpoints.file);
    kernel.SetCheckpointing(ranks.distributed() ? RankFile(file, ranks.rank) : file, every);
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
  if (ranks.distributed() && !gipsi::RealtimeProbes(kernel).empty())
    gipsi::ThrowInputError("command line", "mpirun",
                           "a scene with a real-time HapticProbe cannot run on several ranks");
  if (lead) PrepareOutputDirectory(scene, out, !checkpoints.resume.empty(), overwrite);
  // Every rank writes its pieces of distributed objects' frames: not before rank 0 has
  // prepared (and with --overwrite cleared) the folder.
  if (ranks.distributed()) ranks.barrier();
  gipsi::AttachOutputs(scene, out, !checkpoints.resume.empty(),
                       lead ? gipsi::OutputFiles::kWrite : gipsi::OutputFiles::kReadOnly);
  if (!checkpoints.resume.empty()) {
    if (ranks.distributed()) {
      // On another rank count than wrote the checkpoint, rank q reads rank q % N's file for
      // what every rank holds alike, and split objects read their parts from all N.
      if (ranks.set_checkpoint_files) ranks.set_checkpoint_files(resume_files);
      kernel.ReadCheckpoint(
          resume_files[static_cast<std::size_t>(ranks.rank) % resume_files.size()]);
      if (resume_files.size() == 1 && resume_files.front() == checkpoints.resume)
        gipsi::Log().info(
            "the checkpoint was written by a run on one process: the split objects' state has "
            "moved to this run's {} ranks (docs/scale-out.md, Checkpoints)",
            ranks.size);
      else if (resume_files.size() != static_cast<std::size_t>(ranks.size))
        gipsi::Log().info(
            "the checkpoint was written on {} ranks: the split objects' state has "
            "moved to this run's {} (docs/scale-out.md, Checkpoints)",
            resume_files.size(), ranks.size);
    } else if (!resume_files.empty()) {
      // A distributed run's files: rank 0's for what every rank held alike, every rank's for
      // the objects it split.
      gipsi::SetCheckpointPieces(resume_files);
      try {
        kernel.ReadCheckpoint(resume_files.front());
      } catch (...) {
        gipsi::SetCheckpointPieces({});
        throw;
      }
      gipsi::SetCheckpointPieces({});
      gipsi::Log().info(
          "the checkpoint was written on {} ranks: the split objects' parts are gathered in "
          "this run on one process (docs/scale-out.md, Checkpoints)",
          resume_files.size());
    } else {
      kernel.ReadCheckpoint(checkpoints.resume);
    }
    const double tolerance = 1e-9 * kernel.macro_dt();
    if (scene.end_time <= kernel.time() + tolerance)
      gipsi::ThrowInputError(
          "command line", until > 0 ? "--until" : "--resume",
          fmt::format("the checkpoint {} is at t = {:.6g} s, not before the end of the run at "
                      "{:.6g} s{}: nothing to run (give a later --until)",
                      checkpoints.resume, kernel.time(), scene.end_time,
                      until > 0 ? " (--until)" : " (schedule.end)"));
  }
  // The summary counts this run's steps: a resumed object's counter started at the checkpoint.
  const auto& coordinator = kernel.coordinator();
  std::vector<std::int64_t> steps_before(coordinator.num_objects());
  for (std::size_t i = 0; i < coordinator.num_objects(); ++i)
    steps_before[i] = coordinator.object(i).step_count();
  std::vector<std::int64_t> fired_before(coordinator.num_connectors());
  for (std::size_t i = 0; i < coordinator.num_connectors(); ++i)
    fired_before[i] = coordinator.connector(i).fire_count();

  gipsi::cli::RunProgress progress(quiet, isatty(STDERR_FILENO) != 0, stderr);
  gipsi::RealtimeHaptics haptics(kernel);  // joins the loops however the run ends
  haptics.Start();
  gipsi::RunResult result =
      kernel.Run(scene.end_time, [&](double t, double end) { progress.Update(t, end); });
  haptics.Stop();  // logs each loop's period percentiles
  progress.Done();
  if (ranks.distributed() && (result.outcome == gipsi::RunResult::Outcome::kStopped ||
                              result.outcome == gipsi::RunResult::Outcome::kOutputFailed)) {
    // Not agreed between the ranks (a signal, or a write on rank 0): the others may be inside
    // the next step's collectives. What was written is flushed; end every rank.
    std::cerr << "gipsi: " << (lead ? "" : fmt::format("rank {}: ", ranks.rank))
              << result.diagnostic << "\n";
    ranks.abort(result.outcome == gipsi::RunResult::Outcome::kStopped ? 130 : 4);
  }
  if (!lead) return result.ok() ? 0 : 3;  // an agreed divergence: rank 0 reports it

  std::string summary;
  summary += fmt::format("simulated time:   {:.6g} s (from {:.6g} s)\n",
                         result.end_time - result.start_time, result.start_time);
  summary += fmt::format("wall time:        {:.3f} s\n", result.wall_seconds);
  if (ranks.distributed()) {
    const std::vector<std::string> split = ranks.split_objects();
    summary += fmt::format("MPI ranks:        {} (split over them: {})\n", ranks.size,
                           split.empty() ? std::string("none, every object runs whole on each")
                                         : fmt::format("{}", fmt::join(split, ", ")));
  }
  summary += fmt::format("real-time factor: {:.3g}\n", result.real_time_factor());
  summary +=
      fmt::format("macro steps:      {} of {:.6g} s\n", result.macro_steps, kernel.macro_dt());
  for (std::size_t i = 0; i < coordinator.num_objects(); ++i) {
    const auto& object = coordinator.object(i);
    summary +=
        fmt::format("  {:<20} {:<14} {} steps of {:.6g} s\n", object.name(), object.type_name(),
                    object.step_count() - steps_before[i], coordinator.object_dt(i));
  }
  for (std::size_t i = 0; i < coordinator.num_connectors(); ++i) {
    const auto& connector = coordinator.connector(i);
    summary += fmt::format("  {:<20} {:<14} fired {} times\n", connector.name(),
                           connector.type_name(), connector.fire_count() - fired_before[i]);
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

/// Each connector with its ports and order rules (gipsi/core/port.h), those inside aggregates
/// under the aggregate's name ("heart.cavity_coupling").
void PrintConnectors(const gipsi::Coordinator& coordinator, const std::string& prefix) {
  for (std::size_t i = 0; i < coordinator.num_connectors(); ++i) {
    const auto& connector = coordinator.connector(i);
    std::cout << fmt::format("  connector {:<11} {}\n", prefix + connector.name(),
                             connector.type_name());
    for (const auto& port : connector.ports())
      std::cout << fmt::format("      {}\n", gipsi::DescribePort(port));
    for (const auto& rule : connector.order_rules())
      std::cout << fmt::format("      {}\n", gipsi::DescribeOrderRule(rule));
  }
  for (std::size_t i = 0; i < coordinator.num_objects(); ++i)
    if (const auto* aggregate = dynamic_cast<const gipsi::AggregateObject*>(&coordinator.object(i)))
      PrintConnectors(aggregate->parts(), prefix + aggregate->name() + ".");
}

/// The objects and connectors whose snapshots serialise their state (no state value type, see
/// SimObject::state_is_value), by path, those inside aggregates under the aggregate's name.
void CollectSerialisedStates(const gipsi::Coordinator& coordinator, const std::string& prefix,
                             std::vector<std::string>& out) {
  for (std::size_t i = 0; i < coordinator.num_objects(); ++i) {
    const auto& object = coordinator.object(i);
    if (const auto* aggregate = dynamic_cast<const gipsi::AggregateObject*>(&object))
      CollectSerialisedStates(aggregate->parts(), prefix + object.name() + ".", out);
    else if (!object.state_is_value())
      out.push_back(fmt::format("{}{} ({})", prefix, object.name(), object.type_name()));
  }
  for (std::size_t i = 0; i < coordinator.num_connectors(); ++i) {
    const auto& connector = coordinator.connector(i);
    if (!connector.state_is_value())
      out.push_back(fmt::format("{}{} ({})", prefix, connector.name(), connector.type_name()));
  }
}

int Validate(const std::string& file, const std::vector<std::string>& plugins,
             const gipsi::SceneLimits& limits) {
  gipsi::TypeRegistry registry;
  gipsi::Scene scene = Load(file, plugins, registry, limits, false);
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
  PrintConnectors(coordinator, "");
  std::vector<std::string> serialised;
  CollectSerialisedStates(coordinator, "", serialised);
  std::cout << (serialised.empty()
                    ? std::string("  state: every object and connector keeps it as a value "
                                  "(a step retry copies it)\n")
                    : fmt::format("  state: a step retry serialises {} (no state value type)\n",
                                  fmt::join(serialised, ", ")));
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
  for (const auto& plugin : plugins) registry.LoadPlugin(gipsi::ResolvePlugin(plugin, "."));
  auto print = [](const char* title, const auto& list) {
    std::cout << title << ":\n";
    for (const auto& [name, description] : list)
      std::cout << fmt::format("  {:<18} {}\n", name, description);
  };
  std::cout << "build: gipsi " GIPSI_VERSION_STRING ", " << gipsi::BuildFeatureSummary() << "\n";
  print("objects", registry.objects.List());
  print("connectors", registry.connectors.List());
  print("integrators", registry.integrators.List());
  print("material laws", registry.materials.List());
  // Tables the layers above the kernel declare (cell models, haptic local models by object
  // type, and any a plugin adds).
  for (const std::string& kind : registry.TableKinds())
    print(fmt::format("{}s", kind).c_str(), registry.ListTable(kind));
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
  for (const auto& plugin : plugins) registry.LoadPlugin(gipsi::ResolvePlugin(plugin, "."));
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
      std::cerr << "gipsi: error: " << options.out
                << ": cannot create the file: " << std::strerror(errno) << "\n";
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
    errno = 0;
    csv.close();
    if (!csv) {
      std::cerr << "gipsi: error: " << options.out
                << ": cannot write: " << (errno != 0 ? std::strerror(errno) : "the stream failed")
                << "\n";
      return 4;
    }
    std::cout << "trace:    " << options.out << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"GiPSi: an open-architecture framework for organ-level and surgical simulation"};
  app.set_version_flag("--version", "gipsi " GIPSI_VERSION_STRING " (plugin interface " +
                                        std::to_string(GIPSI_PLUGIN_INTERFACE) + "; " +
                                        gipsi::BuildFeatureSummary() + "; " +
                                        gipsi::SimdKernelsName(gipsi::ActiveSimdKernels()) +
                                        " kernels)");
  app.require_subcommand(1);
  std::string scene_file, out_dir, mesh_file;
  double until = 0;
  bool quiet = false, no_vtu = false, verbose = false, profile = false, overwrite = false;
  std::vector<std::string> plugins;
  app.add_flag("-v,--verbose", verbose, "Log more (debug level)");

  auto* run =
      app.add_subcommand("run", "Run a scene headless, writing VTU/PVD series and probe CSVs");
  run->add_option("SCENE", scene_file, "Scene file (JSON)")->required();
  run->add_option("-o,--out", out_dir, "Output directory (default: the scene's, or out/<scene>)");
  run->add_option("--until", until, "End time in seconds, overriding schedule.end")
      ->check(gipsi::apps::PositiveNumber("a positive number of seconds"));
  run->add_flag("--overwrite", overwrite,
                "Delete the VTU series an earlier run left in the output directory (only the "
                "files GiPSi writes) instead of refusing to run there");
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
      ->check(gipsi::apps::PositiveNumber("a positive number of seconds"));
  run->add_option("--checkpoint", checkpoints.file,
                  "Checkpoint file to write (default: <out>/checkpoint.gck; under mpirun each "
                  "rank writes its own, <stem>_p<rank>.gck)");
  run->add_option("--resume", checkpoints.resume,
                  "Continue from a checkpoint of the same scene, appending to the outputs in the "
                  "output directory (continued outputs are bitwise identical to an "
                  "uninterrupted run with the same thread count; a distributed run's checkpoint "
                  "resumes on the same number of ranks, named as it was written)");

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
      ->check(gipsi::apps::PositiveNumber("a positive number of milliseconds"));
  cell->add_option("--beats", cell_options.protocol.beats, "Number of beats")
      ->capture_default_str()
      ->check(gipsi::apps::IntegerIn(1, 1'000'000, "a whole number of beats from 1 to 1000000"));
  cell->add_option("--dt", cell_options.protocol.dt, "Time step [ms]")
      ->capture_default_str()
      ->check(gipsi::apps::PositiveNumber("a positive number of milliseconds"));
  cell->add_option("--stim-amplitude", cell_options.stim_amplitude,
                   "Stimulus [uA/uF], positive depolarises (default: the model's)")
      ->check(gipsi::apps::FiniteNumber(-HUGE_VAL, false, HUGE_VAL, "a finite number"));
  cell->add_option("--stim-duration", cell_options.stim_duration,
                   "Stimulus duration [ms] (default: the model's)")
      ->check(gipsi::apps::NonNegativeNumber("a non-negative number of milliseconds"));
  cell->add_option("--apd", cell_options.protocol.apd_percent,
                   "Repolarisation level of the APD [%]")
      ->capture_default_str()
      ->check(gipsi::apps::FiniteNumber(0, false, 100, "a percentage in (0, 100]"));
  cell->add_option("--threshold", cell_options.protocol.activation_threshold,
                   "Activation threshold [mV]")
      ->capture_default_str()
      ->check(gipsi::apps::FiniteNumber(-HUGE_VAL, false, HUGE_VAL, "a finite number of mV"));
  cell->add_option("-o,--out", cell_options.out,
                   "Write a CSV trace: t_ms then every state variable");
  cell->add_option("--every", cell_options.every, "Write every K-th step to the CSV")
      ->capture_default_str()
      ->check(gipsi::apps::IntegerIn(1, INT64_MAX, "a positive whole number of steps"));
  cell->add_option("--plugin", plugins, "Load a plugin shared library (repeatable)");

  gipsi::apps::VizCommands viz_commands(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    // CLI11's own codes (105, 106, 109, ...) are not the tool's: a bad command line exits 2.
    std::cerr << "gipsi: error: command line: " << e.what()
              << "\nRun 'gipsi --help' or 'gipsi SUBCOMMAND --help' for the options.\n";
    return 2;
  }
  // -q (run): warnings and errors only; -v: debug lines too.
  gipsi::Log().set_level(quiet     ? spdlog::level::warn
                         : verbose ? spdlog::level::debug
                                   : spdlog::level::info);
  Ranks ranks;
  // Under an MPI launcher with several ranks: PETSc and MPI for the whole run, loaded only then
  // (serial runs never load them), the distributed types, rank 0 printing and writing.
  std::unique_ptr<gipsi::DistributedRun> mpi;
  if (*run && gipsi::apps::LaunchedWithSeveralRanks()) {
#ifdef GIPSI_PARALLEL_LIBRARY
    void* library = dlopen(GIPSI_PARALLEL_LIBRARY, RTLD_NOW | RTLD_GLOBAL);
    const char* why = library == nullptr ? dlerror() : nullptr;
    const auto start = library == nullptr ? nullptr
                                          : reinterpret_cast<gipsi::ParallelStartFunction>(
                                                dlsym(library, gipsi::kParallelStartSymbol));
    if (start == nullptr) {
      std::cerr << "gipsi: error: 'gipsi run' was started on several MPI ranks, and the "
                   "distributed runs' library could not be loaded: "
                << (why != nullptr ? why : dlerror()) << "\n";
      return 1;
    }
    try {
      mpi.reset(start());
    } catch (const std::exception& e) {
      std::cerr << "gipsi: error: starting MPI: " << e.what() << "\n";
      return 1;
    }
    ranks.rank = mpi->rank();
    ranks.size = mpi->size();
    ranks.register_types = [&mpi](gipsi::TypeRegistry& r) { mpi->RegisterTypes(r); };
    ranks.split_objects = [&mpi] { return mpi->split_objects(); };
    ranks.abort = [&mpi](int code) { mpi->Abort(code); };
    ranks.barrier = [&mpi] { mpi->Barrier(); };
    ranks.set_checkpoint_files = [&mpi](std::vector<std::filesystem::path> files) {
      mpi->SetCheckpointFiles(std::move(files));
    };
    // How long a rank that met an error waits for the others to report one too before it
    // ends them all: they read the same scene, so a bad one fails every rank within this; a
    // rank that fails alone costs this much more before the abort.
    ranks.agree_on_failure = [&mpi](const std::string& message) {
      constexpr double kFailureAgreementSeconds = 5.0;
      return mpi->AgreeOnFailure(message, kFailureAgreementSeconds);
    };
    if (ranks.rank != 0) gipsi::Log().set_level(spdlog::level::err);
#else
    // Every rank would run the whole scene and write the same files.
    std::cerr << "gipsi: error: command line: 'gipsi run' was started on several MPI ranks, "
                 "and this gipsi was built without PETSc (docs/scale-out.md: install petsc-dev "
                 "and configure with -DGIPSI_WITH_PETSC=ON). Run it without mpirun.\n";
    return 2;
#endif
  }
  // An error: printed, with the exit code. On several ranks, an error every rank meets (a bad
  // scene, a refused checkpoint) is printed once, by rank 0, and by the others only where their
  // message differs; a rank that fails alone must not leave the others waiting in a collective,
  // so it ends every rank.
  auto fail = [&ranks](int code, const std::string& message) {
    if (!ranks.distributed()) {
      std::cerr << "gipsi: error: " << message << "\n";
      return code;
    }
    const std::optional<std::string> first = ranks.agree_on_failure(message);
    if (ranks.rank == 0 || !first || *first != message)
      std::cerr << "gipsi: error: " << (ranks.rank > 0 ? fmt::format("rank {}: ", ranks.rank) : "")
                << message << "\n";
    if (!first) ranks.abort(code);
    return code;
  };
  try {
    if (*run)
      return Run(scene_file, out_dir, until, quiet, no_vtu, profile, overwrite, plugins,
                 checkpoints, limits, ranks);
    if (*validate) {
      StopSignals signals;  // Ctrl-C while building: exit 130 at once
      return Validate(scene_file, plugins, limits);
    }
    if (*info) return Info(mesh_file);
    if (*types) return Types(plugins);
    if (*cell) return Cell(cell_options, plugins);
    if (auto code = viz_commands.Dispatch()) return *code;
  } catch (const gipsi::InputError& e) {
    return fail(1, e.what());
  } catch (const gipsi::OutputError& e) {
    return fail(4, e.what());
  } catch (const std::filesystem::filesystem_error& e) {
    // Creating the output directory or files (the readers report their own errors as
    // InputError): a write failure.
    return fail(4, gipsi::DescribeFilesystemError(e));
  } catch (const std::exception& e) {
    return fail(1, e.what());
  }
  return 0;
}
