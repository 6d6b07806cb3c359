#pragma once
/// @file
/// A scene loaded in Python (`gipsi.Simulation`): the kernel with its registry, runs with
/// callbacks and Python events, checkpoints to bytes, and the guards against re-entry and other
/// threads.

#include <pybind11/functional.h>
#include <pybind11/pybind11.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/state.h"
#include "gipsi/core/kernel.h"
#include "gipsi/core/registry.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/outputs.h"
#include "gipsi/io/scene.h"
#include "memory_probes.h"
#include "module_util.h"
#include "python_types.h"

namespace gipsi::python {

namespace py = pybind11;

/// A loaded scene with its registry (which must outlive the objects its plugins built).
class Simulation {
 public:
  static std::shared_ptr<Simulation> FromFile(const std::filesystem::path& file,
                                              const std::vector<std::string>& plugins) {
    auto sim = std::shared_ptr<Simulation>(new Simulation(plugins, file.parent_path()));
    sim->scene_ = LoadScene(file, *sim->registry_);
    sim->Attach();
    return sim;
  }
  static std::shared_ptr<Simulation> FromDict(const py::dict& scene, const std::string& name,
                                              const std::filesystem::path& base_dir,
                                              const std::vector<std::string>& plugins) {
    // NumPy arrays and scalars (e.g. a mesh's "nodes" and "tets") go in as JSON arrays and
    // numbers; NaN and infinities are refused here (ValueError) as the JSON reader would.
    const std::string text = ToJsonText(scene);
    auto sim = std::shared_ptr<Simulation>(new Simulation(plugins, base_dir));
    sim->scene_ = LoadSceneFromString(text, name, base_dir, *sim->registry_);
    sim->Attach();
    return sim;
  }

  Kernel& kernel() { return *scene_.kernel; }
  const Scene& scene() const { return scene_; }
  double end_time() const { return scene_.end_time; }
  py::dict probes() const { return probes_->ToDict(); }

  /// Runs to `until` (default: the scene's end). `callback(t)` is called after every macro
  /// step (with the GIL); returning False stops the run there; an exception stops it and is
  /// raised. Ctrl+C stops it too (KeyboardInterrupt).
  /// Refuses `what` while a run is going on, from any thread: the kernel is mid-step (a
  /// callback or an event may not run, restore or schedule).
  void CheckIdle(const char* what) const {
    if (running_)
      throw std::runtime_error(fmt::format(
          "{}: the simulation is running (called from a callback or an event, or another "
          "thread); wait for run() to return",
          what));
  }
  /// Refuses `what` from another thread while a run is going on (a callback or an event of the
  /// running thread may read and write fields and save between macro steps).
  void CheckSameThread(const char* what) const {
    if (running_ && *running_ != std::this_thread::get_id())
      throw std::runtime_error(fmt::format(
          "{}: the simulation is running on another thread; wait for run() to return", what));
  }

  py::dict Run(std::optional<double> until, const py::object& callback) {
    CheckIdle("run");
    if (const std::string& broken = kernel().broken(); !broken.empty())
      throw std::runtime_error(fmt::format(
          "the simulation cannot go on from t = {:.6g} s: {}; restore() a state saved before "
          "(or restore_file() a checkpoint) to continue",
          kernel().time(), broken));
    const double end = until.value_or(scene_.end_time);
    if (!std::isfinite(end))
      throw py::value_error(fmt::format("until must be finite, got {}", end));
    std::optional<py::error_already_set> error;
    Kernel& k = kernel();
    // Without a callback the GIL is taken back only every 0.1 s of wall time (to see Ctrl+C),
    // so another Python thread that holds it does not delay every macro step.
    using Clock = std::chrono::steady_clock;
    auto last_check = Clock::now();
    ProgressFn progress = [&](double t, double) {
      if (callback.is_none()) {
        const auto now = Clock::now();
        if (now - last_check < std::chrono::milliseconds(100)) return;
        last_check = now;
      }
      py::gil_scoped_acquire gil;
      if (error) return;
      try {
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        if (!callback.is_none() && callback(t).is(py::bool_(false))) k.RequestStop();
      } catch (py::error_already_set& e) {
        error.emplace(std::move(e));
        k.RequestStop();
      }
    };
    RunResult result;
    {
      running_ = std::this_thread::get_id();
      const std::shared_ptr<void> not_running(nullptr, [this](void*) { running_.reset(); });
      py::gil_scoped_release release;
      result = k.Run(end, progress);
    }
    if (event_error_) {
      py::error_already_set e = std::move(*event_error_);
      event_error_.reset();
      throw e;
    }
    if (error) throw std::move(*error);
    static const char* outcomes[] = {"completed", "diverged", "stopped", "output_failed"};
    py::dict out;
    out["outcome"] = outcomes[static_cast<int>(result.outcome)];
    out["diagnostic"] = result.diagnostic;
    out["start_time"] = result.start_time;
    out["end_time"] = result.end_time;
    out["wall_seconds"] = result.wall_seconds;
    out["macro_steps"] = result.macro_steps;
    return out;
  }

  /// Schedules `action(sim)` at simulated time `time` (with the GIL), as a scene's events: it
  /// runs at the start of the first macro step at or after `time`. An exception it raises stops
  /// the run and is raised by run().
  void Schedule(const std::shared_ptr<Simulation>& self, double time, py::function action,
                const std::string& description) {
    CheckIdle("schedule");  // the kernel's event list may not change while it fires events
    if (!std::isfinite(time))
      throw py::value_error(fmt::format("an event's time must be finite, got {}", time));
    // The kernel holds the action beyond this call; it refers to the simulation weakly, so
    // the simulation can still be freed.
    std::weak_ptr<Simulation> weak = self;
    auto held = std::make_shared<py::function>(std::move(action));
    kernel().ScheduleEvent({time, description, [weak, held](Kernel&) {
                              py::gil_scoped_acquire gil;
                              auto sim = weak.lock();
                              if (!sim) return;
                              try {
                                (*held)(sim);
                              } catch (py::error_already_set& e) {
                                const std::string what = e.what();
                                sim->event_error_.emplace(std::move(e));
                                throw std::runtime_error(
                                    what);  // stops the run: "event at t = ... failed"
                              }
                            }});
  }

  py::list FiredEvents() {
    py::list out;
    for (const auto& [t, description] : kernel().fired_events())
      out.append(py::make_tuple(t, description));
    return out;
  }

  py::bytes Save() {
    CheckSameThread("save");
    StateWriter out;
    kernel().SaveState(out);
    return py::bytes(out.bytes());
  }
  void Restore(const py::bytes& bytes) {
    CheckIdle("restore");
    StateReader in(std::string(bytes), "checkpoint bytes");
    kernel().RestoreState(in);
  }

  /// Attaches the scene's file outputs (VTU/PVD series, probe CSVs) under `directory` (default:
  /// the scene's outputs.directory).
  void WriteOutputs(const std::optional<std::filesystem::path>& directory) {
    CheckIdle("write_outputs");
    AttachOutputs(scene_, directory.value_or(scene_.output_directory));
  }

 private:
  Simulation(const std::vector<std::string>& plugins, const std::filesystem::path& base_dir)
      : registry_(std::make_unique<TypeRegistry>()) {
    RegisterBuiltins(*registry_);
    RegisterPythonTypes(*registry_);
    for (const auto& plugin : plugins) registry_->LoadPlugin(ResolvePlugin(plugin, base_dir));
  }
  void Attach() {
    auto probes = std::make_unique<MemoryProbes>(scene_.probes);
    probes_ = probes.get();
    scene_.kernel->AddObserver(std::move(probes));
  }

  std::unique_ptr<TypeRegistry> registry_;
  Scene scene_;
  std::optional<py::error_already_set> event_error_;  // raised by the Run it stopped
  std::optional<std::thread::id> running_;            // the thread in Run, while it runs
  MemoryProbes* probes_ = nullptr;
};

}  // namespace gipsi::python
