#include "gipsi/core/kernel.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/base/error.h"
#include "gipsi/base/json_node.h"
#include "gipsi/base/log.h"
#include "gipsi/core/aggregate.h"

namespace gipsi {

void Kernel::ScheduleEvent(ScheduledEvent event) {
  if (!std::isfinite(event.time))
    throw InputError(fmt::format("event '{}': time is not finite", event.description));
  auto pos =
      std::upper_bound(events_.begin() + static_cast<std::ptrdiff_t>(next_event_), events_.end(),
                       event.time, [](double t, const ScheduledEvent& e) { return t < e.time; });
  events_.insert(pos, std::move(event));
}

void Kernel::AddObserver(std::unique_ptr<Observer> observer) {
  GIPSI_CHECK(observer != nullptr);
  observers_.push_back(std::move(observer));
}

void Kernel::Initialize(double macro_dt) {
  if (coordinator_.num_objects() == 0) throw InputError("the scene has no objects to simulate");
  macro_dt_ = macro_dt > 0 ? macro_dt : coordinator_.max_object_dt();
  coordinator_.Prepare(macro_dt_);
  // Long steps (Newton iterations, load steps) poll the stop request inside the step.
  coordinator_.SetStopToken(StopToken(&stop_requested_));
}

namespace {

void CollectPaths(const std::string& prefix, const SimObject& object,
                  std::vector<std::pair<std::string, SimObject*>>& out) {
  const std::string path = prefix.empty() ? object.name() : prefix + "." + object.name();
  // The kernel owns its objects and hands them out mutable (as FindObject always has).
  out.emplace_back(path, const_cast<SimObject*>(&object));
  if (const auto* aggregate = dynamic_cast<const AggregateObject*>(&object))
    for (std::size_t i = 0; i < aggregate->parts().num_objects(); ++i)
      CollectPaths(path, aggregate->parts().object(i), out);
}

}  // namespace

std::vector<std::pair<std::string, SimObject*>> Kernel::ObjectPaths() const {
  std::vector<std::pair<std::string, SimObject*>> paths;
  for (std::size_t i = 0; i < coordinator_.num_objects(); ++i)
    CollectPaths("", coordinator_.object(i), paths);
  return paths;
}

std::string Kernel::ObjectPath(const SimObject& object) const {
  for (const auto& [path, o] : ObjectPaths())
    if (o == &object) return path;
  return object.name();
}

SimObject& Kernel::FindObject(std::string_view name) const {
  if (SimObject* object = coordinator_.FindObject(name)) return *object;
  const auto paths = ObjectPaths();
  std::vector<std::string> names, candidates, matches;
  SimObject* match = nullptr;
  for (const auto& [path, object] : paths) {
    names.push_back(path);
    candidates.push_back(path);
    if (path != object->name()) candidates.push_back(object->name());
    if (object->name() == name) {  // a part by its own name
      matches.push_back(path);
      match = object;
    }
  }
  if (matches.size() == 1) return *match;
  if (matches.size() > 1)
    throw InputError(fmt::format("object name '{}' is ambiguous: it could be {}", name,
                                 fmt::join(matches, " or ")));
  throw InputError(fmt::format("no object named '{}'{}; objects: {}", name,
                               SuggestClosest(name, candidates), fmt::join(names, ", ")));
}

void Kernel::FireDueEvents(double t) {
  const double tolerance = 1e-9 * macro_dt_;
  while (next_event_ < events_.size() && events_[next_event_].time <= t + tolerance) {
    ScheduledEvent& event = events_[next_event_++];
    Log().info("t = {:.6g} s: event: {}", t, event.description);
    event.action(*this);
    fired_.emplace_back(t, event.description);
  }
}

void Kernel::Notify(double t) {
  const auto start = std::chrono::steady_clock::now();
  for (auto& observer : observers_) observer->Observe(*this, t);
  output_seconds_ +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

RunResult Kernel::Run(double end_time, const ProgressFn& progress) {
  GIPSI_CHECK(macro_dt_ > 0, "Kernel::Initialize was not called");
  using Clock = std::chrono::steady_clock;
  const auto wall_start = Clock::now();
  // A stop requested before this Run (e.g. by a signal while the outputs were being attached)
  // stops it after its first macro step; the request is used up when the run ends.
  RunResult result;
  result.start_time = time();
  const auto last_step =
      static_cast<std::int64_t>(std::ceil((end_time - start_time_) / macro_dt_ - 1e-9));

  if (!broken_.empty()) {
    result.outcome = RunResult::Outcome::kStopped;
    result.diagnostic = fmt::format(
        "the simulation cannot go on from t = {:.6g} s: {}; restore a checkpoint to continue",
        time(), broken_);
    result.end_time = time();
    return result;
  }
  // The failure policy's roll-back (when active) leaves every object at the macro step's start.
  const bool rolls_back = policy_.max_halvings > 0;
  auto finish = [&](RunResult::Outcome outcome, std::string diagnostic) {
    for (auto& observer : observers_) {
      try {
        observer->Finish(*this);
      } catch (const std::exception& e) {
        if (outcome == RunResult::Outcome::kCompleted) {
          outcome = RunResult::Outcome::kOutputFailed;
          diagnostic = fmt::format("writing outputs failed: {}", e.what());
        }
      }
    }
    stop_requested_.store(false);
    result.outcome = outcome;
    result.diagnostic = std::move(diagnostic);
    result.end_time = time();
    result.wall_seconds = std::chrono::duration<double>(Clock::now() - wall_start).count();
    return result;
  };

  try {
    if (!started_) {
      started_ = true;
      FireDueEvents(time());
      Notify(time());
    }
  } catch (const std::exception& e) {
    return finish(RunResult::Outcome::kOutputFailed, e.what());
  }

  while (macro_index_ < last_step) {
    const double t = time();
    try {
      FireDueEvents(t);
    } catch (const std::exception& e) {
      // Every object is still at t (what the event changed before failing is the event's).
      return finish(RunResult::Outcome::kStopped,
                    fmt::format("event at t = {:.6g} s failed: {}", t, e.what()));
    }
    std::string retry_note;
    std::optional<ScheduleFailure> failure;
    try {
      failure = StepWithPolicy(t, retry_note);
    } catch (const std::exception& e) {
      // A state that cannot be saved for roll-back (StepWithPolicy says so), or a step or
      // connector that broke its never-throw contract (a plugin's, a Python object's field).
      broken_ = fmt::format("the macro step at t = {:.6g} s was left part-way by an exception", t);
      return finish(
          RunResult::Outcome::kStopped,
          fmt::format("the macro step at t = {:.6g} s could not be done: {}", t, e.what()));
    }
    if (failure && !rolls_back)
      broken_ =
          fmt::format("{} '{}' {} inside the macro step at t = {:.6g} s",
                      failure->is_connector ? "connector" : "object", failure->who,
                      failure->status.code == StepStatus::Code::kStopped ? "stopped" : "failed", t);
    if (failure && failure->status.code == StepStatus::Code::kStopped) {
      // A stop request reached inside a step (StopToken): the object abandoned it. Objects
      // before it in the order may have advanced, so no checkpoint is written at this stop
      // (the failure policy's roll-back, when active, has restored every object to t).
      return finish(
          RunResult::Outcome::kStopped,
          fmt::format("stopped on request at t = {:.6g} s, inside the step of {} '{}' "
                      "(abandoned); outputs written up to t = {:.6g} s are kept{}",
                      failure->time, failure->is_connector ? "connector" : "object", failure->who,
                      t, checkpoint_every_ > 0 ? "; no checkpoint was written at the stop" : ""));
    }
    if (failure) {
      const std::string& detail = failure->detail;
      std::string where =
          failure->status.item >= 0
              ? fmt::format(" (item {}, value {:.6g})", failure->status.item, failure->status.value)
              : std::string();
      return finish(
          RunResult::Outcome::kDiverged,
          fmt::format("{} '{}'{} {} at t = {:.6g} s (macro step {}): {}{}; the run was "
                      "stopped, outputs written up to t = {:.6g} s are kept{}",
                      failure->is_connector ? "connector" : "object", failure->who,
                      detail.empty() ? "" : " (" + detail + ")",
                      failure->status.code == StepStatus::Code::kDiverged ? "diverged" : "failed",
                      failure->time, macro_index_, failure->status.what, where, t, retry_note));
    }
    ++macro_index_;
    ++result.macro_steps;
    try {
      Notify(time());
    } catch (const std::exception& e) {
      return finish(RunResult::Outcome::kOutputFailed,
                    fmt::format("writing outputs failed at t = {:.6g} s: {}", time(), e.what()));
    }
    if (progress) progress(time(), end_time);
    const bool stop = stop_requested_.load();
    if (checkpoint_every_ > 0 && (stop || macro_index_ % checkpoint_every_ == 0)) {
      try {
        WriteCheckpoint(checkpoint_file_);
      } catch (const std::exception& e) {
        return finish(
            RunResult::Outcome::kOutputFailed,
            fmt::format("writing the checkpoint failed at t = {:.6g} s: {}", time(), e.what()));
      }
    }
    if (stop) {
      return finish(
          RunResult::Outcome::kStopped,
          fmt::format("stopped on request at t = {:.6g} s{}", time(),
                      checkpoint_every_ > 0 ? "; checkpoint written to " + checkpoint_file_.string()
                                            : std::string()));
    }
  }
  return finish(RunResult::Outcome::kCompleted, "");
}

}  // namespace gipsi
