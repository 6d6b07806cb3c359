#pragma once
/// @file
/// `Kernel`: owns the object pool (through a Coordinator), runs the macro-step loop with
/// multi-rate sub-stepping, fires scheduled discrete events, notifies observers (output writers,
/// probes) and applies the divergence policy (FailurePolicy): a failing object stops the run
/// with a diagnostic, or the macro step is rolled back and retried with halved steps; everything
/// already written stays written. Writes and restores checkpoints of the whole run
/// (kernel_state.cc).

#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/object_state.h"
#include "gipsi/core/coordinator.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class Kernel;
class StateReader;
class StateWriter;

/// Something that watches the run: output writers and probes. Observe is called once before
/// the first step (at the start time) and after every macro step; an observer decides itself
/// whether it is due. Observers may throw std::exception (e.g. a full disk): the kernel stops
/// the run with that message.
class Observer {
 public:
  virtual ~Observer() = default;
  virtual void Observe(const Kernel& kernel, double t) = 0;
  /// Called once when the run ends, however it ends (flush files here).
  virtual void Finish(const Kernel& /*kernel*/) {}
  /// Checkpoints: where the observer is (next output time, frame numbers, file lengths), so a
  /// resumed run continues its files exactly. Called between macro steps. The defaults throw
  /// InputError("this output does not support checkpoints").
  virtual void SaveState(StateWriter& out);
  virtual void RestoreState(StateReader& in);
  /// Called once the whole checkpoint was read and checked (every RestoreState succeeded). Only
  /// here may a restored observer change its files (cut them back, rewrite collections), so a
  /// refused checkpoint leaves every output file as it was. Default: nothing.
  virtual void CommitRestore() {}
};

/// What the kernel does when an object or connector fails a macro step (scene key
/// "schedule.on_failure"). Plain struct.
struct FailurePolicy {
  /// 0: stop with a diagnostic (the default). N > 0: roll the macro step back and retry it as 2,
  /// 4, ... 2^N steps of half, a quarter, ... the size (every object's sub-step shrinks alike)
  /// before stopping.
  int max_halvings = 0;
};

/// A discrete event scheduled at a simulated time, e.g. "at t = 0.5 s release the clamp".
struct ScheduledEvent {
  double time = 0;
  std::string description;
  std::function<void(Kernel&)> action;
};

/// How a run ended.
struct RunResult {
  enum class Outcome { kCompleted, kDiverged, kStopped, kOutputFailed };
  Outcome outcome = Outcome::kCompleted;
  std::string diagnostic;  ///< empty when completed
  double start_time = 0, end_time = 0;
  double wall_seconds = 0;
  std::int64_t macro_steps = 0;
  [[nodiscard]] bool ok() const { return outcome == Outcome::kCompleted; }
  /// Simulated seconds per wall-clock second.
  [[nodiscard]] double real_time_factor() const {
    return wall_seconds > 0 ? (end_time - start_time) / wall_seconds : 0;
  }
};

/// Progress callback: (current time, end time). Called after each macro step.
using ProgressFn = std::function<void(double, double)>;

/// The simulation kernel. Not copyable or movable (observers and events hold references).
///
/// Build: add objects and connectors to `coordinator()`, events, observers; then `Initialize`.
/// Run: `Run(end_time)`; may be called again to continue.
class Kernel {
 public:
  Kernel() = default;
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

  [[nodiscard]] Coordinator& coordinator() { return coordinator_; }
  [[nodiscard]] const Coordinator& coordinator() const { return coordinator_; }

  /// Schedules `event`; events fire at the start of the first macro step whose start time is
  /// >= event.time (to within 1e-9 of the macro step), in time order, ties in insertion order.
  void ScheduleEvent(ScheduledEvent event);
  void AddObserver(std::unique_ptr<Observer> observer);

  /// Fixes the macro step: `macro_dt` if > 0, else the largest object dt. Throws InputError if
  /// an object's dt does not divide it.
  void Initialize(double macro_dt = 0);
  [[nodiscard]] double macro_dt() const { return macro_dt_; }
  /// Sets the divergence policy (before Run).
  void SetFailurePolicy(FailurePolicy policy) { policy_ = policy; }
  [[nodiscard]] const FailurePolicy& failure_policy() const { return policy_; }
  /// Macro steps that failed and were retried with smaller steps, so far.
  [[nodiscard]] std::int64_t retried_steps() const { return retried_; }

  /// Writes a checkpoint to `file` every `every` macro steps (> 0) during Run, and when a run
  /// is stopped on request. Atomic: a crash mid-write leaves the previous checkpoint.
  void SetCheckpointing(std::filesystem::path file, std::int64_t every);
  /// The complete state between macro steps: clock, event queue position, every object and
  /// connector, and every observer's position. Coupling loads are not state (the next macro
  /// step clears them) and are left as they are. Throws InputError if an object, connector or
  /// observer does not support checkpoints.
  void SaveState(StateWriter& out);
  /// Restores what SaveState wrote for the same scene (after Initialize and AddObserver, before
  /// Run); throws InputError naming what differs for a checkpoint of another scene.
  void RestoreState(StateReader& in);
  /// SaveState into a checkpoint file (gipsi/base/state.h: atomic, checksummed).
  void WriteCheckpoint(const std::filesystem::path& file);
  /// RestoreState from a checkpoint file.
  void ReadCheckpoint(const std::filesystem::path& file);

  /// Runs until `end_time` (rounded to a whole number of macro steps). Never throws for a
  /// numerical failure: the outcome and diagnostic say what happened.
  RunResult Run(double end_time, const ProgressFn& progress = {});
  /// Why the simulation cannot go on from its state, or empty. A run that ends inside a macro
  /// step without the failure policy's roll-back (an object or connector failed, a step was
  /// abandoned at a stop request, an exception inside the step) leaves some objects advanced
  /// and others not; so does a checkpoint restored only in part. Run then refuses to step
  /// (outcome stopped, saying so) until a checkpoint is restored.
  [[nodiscard]] const std::string& broken() const { return broken_; }
  /// Asks `Run` to stop after its current macro step, also when asked before it (thread- and
  /// signal-safe). Objects that poll their stop token (SimObject::stop_token; FemSolid between
  /// load steps and Newton iterations) abandon their step instead: the run then ends inside the
  /// macro step, "stopped on request", without a checkpoint at the stop.
  void RequestStop() { stop_requested_.store(true); }

  [[nodiscard]] double time() const { return start_time_ + macro_index_ * macro_dt_; }
  [[nodiscard]] std::int64_t macro_steps() const { return macro_index_; }
  /// Wall-clock seconds spent in observers (probes, output files) so far.
  [[nodiscard]] double output_seconds() const { return output_seconds_; }
  /// Descriptions and times of the events fired so far.
  [[nodiscard]] const std::vector<std::pair<double, std::string>>& fired_events() const {
    return fired_;
  }
  /// The object called `name`: the one naming scheme of scenes, probes, the command line and
  /// the viewer. An object's name is its full dotted path ("heart.bioelectricity" for the part
  /// `bioelectricity` of the aggregate `heart`); a part's own name ("bioelectricity") is accepted
  /// too when exactly one object or part has it. Throws InputError listing every object and part
  /// by its full name when there is none, or naming the candidates when a short name is
  /// ambiguous.
  [[nodiscard]] SimObject& FindObject(std::string_view name) const;
  /// The full dotted name of every object and part, depth first (an aggregate before its
  /// parts), with the object.
  [[nodiscard]] std::vector<std::pair<std::string, SimObject*>> ObjectPaths() const;
  /// The full dotted name of `object` (FindObject finds it by it); its own name if it is not in
  /// this kernel.
  [[nodiscard]] std::string ObjectPath(const SimObject& object) const;

 private:
  void FireDueEvents(double t);
  void Notify(double t);
  /// One macro step from time t under the failure policy; the failure if it could not be done.
  std::optional<ScheduleFailure> StepWithPolicy(double t, std::string& retry_note);

  Coordinator coordinator_;
  std::vector<ScheduledEvent> events_;  // sorted by time (stable)
  std::size_t next_event_ = 0;
  std::vector<std::unique_ptr<Observer>> observers_;
  std::vector<std::pair<double, std::string>> fired_;
  double macro_dt_ = 0;
  double output_seconds_ = 0;
  double start_time_ = 0;
  std::int64_t macro_index_ = 0;
  bool started_ = false;
  std::string broken_;  // see broken()
  FailurePolicy policy_;
  std::int64_t retried_ = 0;
  // The whole simulation at the start of the current macro step (retry policy): one snapshot,
  // made at the first retried step and copied into at every one after.
  std::unique_ptr<ObjectState> rollback_;
  std::filesystem::path checkpoint_file_;
  std::int64_t checkpoint_every_ = 0;
  std::atomic<bool> stop_requested_{false};
};

}  // namespace gipsi
GIPSI_EXPORT_END
