/// @file
/// Kernel checkpoints (state of the whole run) and the roll-back failure policy.

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/core/kernel.h"

namespace gipsi {
namespace {

void SaveSimulation(const Coordinator& c, StateWriter& out) {
  out.WriteInt(static_cast<std::int64_t>(c.num_objects()));
  out.WriteInt(static_cast<std::int64_t>(c.num_connectors()));
  for (std::size_t i = 0; i < c.num_objects(); ++i) c.object(i).SaveState(out);
  for (std::size_t i = 0; i < c.num_connectors(); ++i) c.connector(i).SaveState(out);
}

void RestoreSimulation(Coordinator& c, StateReader& in) {
  const std::int64_t objects = in.ReadInt(), connectors = in.ReadInt();
  if (objects != static_cast<std::int64_t>(c.num_objects()) ||
      connectors != static_cast<std::int64_t>(c.num_connectors()))
    in.Fail(fmt::format("the checkpoint has {} objects and {} connectors, this scene {} and {}",
                        objects, connectors, c.num_objects(), c.num_connectors()));
  for (std::size_t i = 0; i < c.num_objects(); ++i) c.object(i).RestoreState(in);
  for (std::size_t i = 0; i < c.num_connectors(); ++i) c.connector(i).RestoreState(in);
}

/// "name (Type), ..." of the top-level objects and connectors: a quick check that a
/// checkpoint belongs to this scene, with a readable message when it does not.
std::string SceneSignature(const Coordinator& c) {
  std::string s;
  for (std::size_t i = 0; i < c.num_objects(); ++i)
    s += fmt::format("{}{} ({})", s.empty() ? "" : ", ", c.object(i).name(),
                     c.object(i).type_name());
  for (std::size_t i = 0; i < c.num_connectors(); ++i)
    s += fmt::format("{}{} ({})", s.empty() ? "" : ", ", c.connector(i).name(),
                     c.connector(i).type_name());
  return s;
}

}  // namespace

void Observer::SaveState(StateWriter& /*out*/) {
  throw InputError("an output of this run does not support checkpoints");
}

void Observer::RestoreState(StateReader& /*in*/) {
  throw InputError("an output of this run does not support checkpoints");
}

void Kernel::SetCheckpointing(std::filesystem::path file, std::int64_t every) {
  GIPSI_CHECK(every > 0);
  checkpoint_file_ = std::move(file);
  checkpoint_every_ = every;
}

void Kernel::SaveState(StateWriter& out) {
  GIPSI_CHECK(macro_dt_ > 0, "Kernel::Initialize was not called");
  out.BeginSection("Kernel", 1);
  out.WriteString(SceneSignature(coordinator_));
  out.WriteDouble(macro_dt_);
  out.WriteDouble(start_time_);
  out.WriteInt(macro_index_);
  out.WriteBool(started_);
  out.WriteInt(static_cast<std::int64_t>(events_.size()));
  out.WriteInt(static_cast<std::int64_t>(next_event_));
  out.WriteInt(static_cast<std::int64_t>(fired_.size()));
  for (const auto& [t, what] : fired_) {
    out.WriteDouble(t);
    out.WriteString(what);
  }
  out.WriteInt(retried_);
  SaveSimulation(coordinator_, out);
  out.WriteInt(static_cast<std::int64_t>(observers_.size()));
  for (auto& observer : observers_) observer->SaveState(out);
  out.EndSection();
}

void Kernel::RestoreState(StateReader& in) {
  GIPSI_CHECK(macro_dt_ > 0, "Kernel::Initialize was not called");
  in.BeginSection("Kernel", 1);
  const std::string signature = in.ReadString(), expected = SceneSignature(coordinator_);
  if (signature != expected)
    in.Fail(
        fmt::format("the checkpoint was written for another scene (objects and connectors: "
                    "{}; this scene: {})",
                    signature, expected));
  const double macro_dt = in.ReadDouble();
  if (macro_dt != macro_dt_)
    in.Fail(
        fmt::format("the checkpoint's macro step is {} s, this scene's {} s", macro_dt, macro_dt_));
  // The kernel's own fields are read into locals and set only once everything was read: a
  // checkpoint refused before the objects leaves the simulation as it was.
  const double start_time = in.ReadDouble();
  const std::int64_t macro_index = in.ReadInt();
  const bool started = in.ReadBool();
  const std::int64_t events = in.ReadInt();
  if (events != static_cast<std::int64_t>(events_.size()))
    in.Fail(fmt::format("the checkpoint has {} scheduled events, this scene {}", events,
                        events_.size()));
  const auto next_event = static_cast<std::size_t>(in.ReadInt());
  if (next_event > events_.size()) in.Fail("corrupted event queue position");
  std::vector<std::pair<double, std::string>> fired_events;
  const std::int64_t fired = in.ReadInt();
  if (fired < 0 || fired > events) in.Fail("corrupted list of fired events");
  for (std::int64_t i = 0; i < fired; ++i) {
    const double t = in.ReadDouble();
    fired_events.emplace_back(t, in.ReadString());
  }
  const std::int64_t retried = in.ReadInt();
  try {
    RestoreSimulation(coordinator_, in);
    const std::int64_t observers = in.ReadInt();
    if (observers != static_cast<std::int64_t>(observers_.size()))
      in.Fail(
          fmt::format("the checkpoint has {} outputs, this run {} (were the same outputs "
                      "enabled?)",
                      observers, observers_.size()));
    for (auto& observer : observers_) observer->RestoreState(in);
    in.EndSection();
    if (!in.at_end()) in.Fail("unexpected data after the kernel state");
  } catch (const std::exception& e) {
    // Some objects may hold the checkpoint's state and others not.
    broken_ = fmt::format("a checkpoint was restored only in part ({})", e.what());
    throw;
  }
  start_time_ = start_time;
  macro_index_ = macro_index;
  started_ = started;
  next_event_ = next_event;
  fired_ = std::move(fired_events);
  retried_ = retried;
  broken_.clear();
  for (auto& observer : observers_) observer->CommitRestore();
}

void Kernel::WriteCheckpoint(const std::filesystem::path& file) {
  StateWriter out;
  SaveState(out);
  WriteCheckpointFile(file, out.bytes());
  Log().debug("t = {:.6g} s: checkpoint written to {}", time(), file.string());
}

void Kernel::ReadCheckpoint(const std::filesystem::path& file) {
  StateReader in(ReadCheckpointFile(file), file.string());
  RestoreState(in);
  Log().info("resumed from {} at t = {:.6g} s (macro step {})", file.string(), time(),
             macro_index_);
}

std::optional<ScheduleFailure> Kernel::StepWithPolicy(double t, std::string& retry_note) {
  coordinator_.BeginMacroStep();
  if (policy_.max_halvings <= 0) return coordinator_.MacroStep(t, macro_index_);
  try {
    if (rollback_)
      coordinator_.TakeSnapshot(*rollback_);
    else
      rollback_ = coordinator_.NewSnapshot();
  } catch (const InputError& e) {
    throw InputError(fmt::format("the failure policy needs checkpoints: {}", e.what()));
  }
  auto restore = [&] { coordinator_.RestoreSnapshot(*rollback_); };
  std::optional<ScheduleFailure> failure = coordinator_.MacroStep(t, macro_index_);
  auto stopped = [&] { return failure && failure->status.code == StepStatus::Code::kStopped; };
  for (int h = 1; failure && !stopped() && h <= policy_.max_halvings; ++h) {
    const int split = 1 << h;
    Log().warn("t = {:.6g} s: {} '{}' failed ({}); retrying the macro step as {} steps of {:.6g} s",
               failure->time, failure->is_connector ? "connector" : "object", failure->who,
               failure->status.what, split, macro_dt_ / split);
    restore();
    failure.reset();
    for (int j = 0; j < split && !failure; ++j) {
      coordinator_.BeginMacroStep();
      failure = coordinator_.MacroStep(t + j * (macro_dt_ / split), macro_index_, split);
    }
    if (!failure) ++retried_;
  }
  if (stopped()) {
    const ScheduleFailure last = *failure;
    restore();  // every object back at t: a consistent state
    return last;
  }
  if (failure) {
    retry_note = fmt::format(" (also with the macro step halved {} times)", policy_.max_halvings);
    const ScheduleFailure last = *failure;
    restore();  // leave the last good state, not a non-finite one
    return last;
  }
  for (std::size_t i = 0; i < coordinator_.num_objects(); ++i)
    coordinator_.object(i).SetTime(t + macro_dt_);
  return std::nullopt;
}

}  // namespace gipsi
