#include "viewer/simulation_thread.h"

#include <chrono>
#include <iostream>
#include <limits>

#include <fmt/format.h>

#include "gipsi/base/json_node.h"
#include "gipsi/base/log.h"
#include "gipsi/core/local_model.h"
#include "gipsi/haptics/haptic_probe.h"
#include "gipsi/viz/plot_data.h"

namespace gipsi::viz {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::size_t kMaxTraceSamples = 2000;

}  // namespace

SimulationThread::SimulationThread(LoadFn load,
                                   std::vector<std::pair<std::string, ColorSpec>> colors,
                                   LatestValue<FrameBuffers>& frames,
                                   const std::vector<std::string>& show,
                                   const std::vector<std::string>& hide)
    : load_(std::move(load)), initial_colors_(std::move(colors)), frames_(frames) {
  Load(initial_colors_);  // throws on bad input, before any thread exists
  std::vector<std::string> names;
  for (std::size_t i = 0; i < display_->size(); ++i) {
    names.push_back(display_->manager(i).name());
    initially_hidden_.push_back(!display_->manager(i).draw().visible);
  }
  ApplyVisibility(*scene_->kernel, names, show, hide, initially_hidden_);
  Publish();
  thread_ = std::thread([this] { Loop(); });
}

SimulationThread::~SimulationThread() {
  quit_.store(true);
  wake_.notify_all();
  thread_.join();
  tool_.Release();
}

void SimulationThread::Load(const std::vector<std::pair<std::string, ColorSpec>>& colors) {
  tool_.Release();
  auto registry = std::make_unique<TypeRegistry>();
  auto scene = std::make_unique<Scene>(load_(*registry));
  auto display = std::make_unique<SceneDisplay>(*scene->kernel, scene->display, colors);
  {
    std::lock_guard lock(mutex_);
    mouse_ = nullptr;
  }
  haptics_.reset();  // joins the old scene's real-time haptic loops before the scene goes
  scene_ = std::move(scene);
  registry_ = std::move(registry);
  display_ = std::move(display);
  // Real-time probes tick from the load on, playing or paused (paused, their models go stale
  // and the watchdog fades the force out).
  haptics_ = std::make_unique<RealtimeHaptics>(*scene_->kernel);
  haptics_->Start();
  MouseDevice* mouse = nullptr;
  Coordinator& coordinator = scene_->kernel->coordinator();
  for (std::size_t i = 0; i < coordinator.num_objects() && mouse == nullptr; ++i)
    if (auto* probe = dynamic_cast<HapticProbe*>(&coordinator.object(i)))
      mouse = probe->mouse_device();
  {
    std::lock_guard lock(mutex_);
    mouse_ = mouse;
  }
  traces_.clear();
  trace_probes_.clear();
  for (std::size_t p = 0; p < scene_->probes.size(); ++p) {
    const Probe& probe = scene_->probes[p];
    if (probe.is_line()) continue;  // a profile along a line, not a trace over time
    trace_probes_.push_back(p);
    ProbeTrace trace;
    trace.name = probe.name;
    const auto columns = ProbeColumns(probe);
    trace.columns.assign(columns.begin() + 1, columns.end());  // after "time"
    for (const std::string& column : trace.columns) {
      const ColumnDisplay shown = DisplayOfColumn(probe, column, scene_->plots);
      trace.labels.push_back(shown.label);
      trace.units.push_back(shown.unit);
      trace.scales.push_back(shown.scale);
      trace.no_data.push_back(shown.no_data.value_or(std::numeric_limits<double>::quiet_NaN()));
    }
    trace.values.resize(trace.columns.size());
    traces_.push_back(std::move(trace));
  }
  UpdateStatus([&](SimulationStatus& s) {
    s.time = scene_->kernel->time();
    s.end_time = scene_->end_time;
    s.macro_dt = scene_->kernel->macro_dt();
    s.haptic_mouse = mouse != nullptr;
    s.objects.clear();
    s.draws.clear();
    for (std::size_t i = 0; i < display_->size(); ++i) {
      s.draws.push_back(display_->manager(i).draw());
      const SimObject& object = display_->manager(i).object();
      std::vector<std::string> fields;
      std::vector<int> components;
      for (const FieldInfo& f : object.fields())
        if (f.name == s.draws.back().color.field || OffersField(object, object.FindField(f.name))) {
          fields.push_back(f.name);
          components.push_back(f.components);
        }
      // Pulled is the tissue it is drawn on (a heart's bioelectricity: its muscle).
      const SimObject& tissue = display_->manager(i).geometry_object();
      const auto external = tissue.TryFindField("external_force");
      const bool pullable = LocalModels(*registry_).Contains(tissue.type_name()) && external &&
                            tissue.field_info(*external).writable() &&
                            tissue.boundary().num_vertices() > 0;
      s.objects.push_back(
          {display_->manager(i).name(), std::move(fields), std::move(components), pullable});
    }
  });
}

void SimulationThread::Publish() {
  FrameBuffers& frame = frames_.back();
  display_->Fill(scene_->kernel->time(), frame);
  // Probe samples: appended here, at most kMaxTraceSamples kept (the oldest half dropped).
  for (std::size_t p = 0; p < traces_.size(); ++p) {
    ProbeTrace& trace = traces_[p];
    if (!trace.time.empty() && float(scene_->kernel->time()) <= trace.time.back()) continue;
    scene_->probes[trace_probes_[p]].Sample(sample_);
    if (trace.time.size() >= kMaxTraceSamples) {
      const auto half = static_cast<std::ptrdiff_t>(kMaxTraceSamples / 2);
      trace.time.erase(trace.time.begin(), trace.time.begin() + half);
      for (auto& v : trace.values) v.erase(v.begin(), v.begin() + half);
    }
    trace.time.push_back(float(scene_->kernel->time()));
    for (std::size_t c = 0; c < trace.values.size() && c < sample_.size(); ++c)
      trace.values[c].push_back(float(sample_[c]));
  }
  frame.traces = traces_;
  frames_.Publish();
}

void SimulationThread::Report(const std::string& message, bool failed) {
  std::cerr << "gipsi: error: " << message << std::endl;
  UpdateStatus([&](SimulationStatus& s) {
    s.message = message;
    s.failed = s.failed || failed;
  });
}

void SimulationThread::UpdateStatus(const std::function<void(SimulationStatus&)>& change) {
  std::lock_guard lock(mutex_);
  change(status_);
}

SimulationStatus SimulationThread::status() const {
  std::lock_guard lock(mutex_);
  return status_;
}

void SimulationThread::SetPlaying(bool playing) {
  std::lock_guard lock(mutex_);
  if (playing && status_.at_end) commands_.reset = true;  // paused at the end: play it again
  commands_.playing = playing;
  commands_.run_until = -1;
  wake_.notify_all();
}
void SimulationThread::Step() {
  std::lock_guard lock(mutex_);
  commands_.playing = false;
  ++commands_.steps;
  wake_.notify_all();
}
void SimulationThread::Reset() {
  std::lock_guard lock(mutex_);
  commands_.playing = false;
  commands_.steps = 0;
  commands_.reset = true;
  wake_.notify_all();
}
void SimulationThread::SetSpeed(double real_time_factor) {
  std::lock_guard lock(mutex_);
  commands_.speed = real_time_factor;
}
void SimulationThread::SetAtEnd(AtEnd at_end) {
  std::lock_guard lock(mutex_);
  commands_.at_end = at_end;
}
void SimulationThread::SetColor(std::size_t surface, ColorSpec spec) {
  std::lock_guard lock(mutex_);
  commands_.colors.emplace_back(surface, std::move(spec));
  wake_.notify_all();
}
void SimulationThread::Grab(std::size_t surface, const Vec3& point) {
  std::lock_guard lock(mutex_);
  commands_.tool = 1;
  commands_.tool_surface = surface;
  commands_.tool_point = point;
  commands_.tool_target = point;
  commands_.tool_target_new = false;
  wake_.notify_all();
}
void SimulationThread::Drag(const Vec3& target) {
  std::lock_guard lock(mutex_);
  commands_.tool_target = target;
  commands_.tool_target_new = true;
  wake_.notify_all();
}
void SimulationThread::ReleaseTool() {
  std::lock_guard lock(mutex_);
  commands_.tool = 2;
  wake_.notify_all();
}
void SimulationThread::HapticBeginDrag(const Vec3& view_direction) {
  std::lock_guard lock(mutex_);
  if (mouse_) mouse_->BeginDrag(view_direction);
}
void SimulationThread::HapticDragTo(const Vec3& origin, const Vec3& direction) {
  std::lock_guard lock(mutex_);
  if (mouse_) (void)mouse_->DragTo(origin, direction);
}
void SimulationThread::HapticEndDrag() {
  std::lock_guard lock(mutex_);
  if (mouse_) mouse_->EndDrag();
}
void SimulationThread::HapticPush(const Vec3& view_direction, double notches) {
  std::lock_guard lock(mutex_);
  if (mouse_) mouse_->Push(view_direction, notches);
}
std::optional<std::pair<Vec3, Vec3>> SimulationThread::HapticTool() {
  std::lock_guard lock(mutex_);
  if (!mouse_) return std::nullopt;
  return std::make_pair(mouse_->position(), mouse_->TakeForce());
}
void SimulationThread::RunUntil(double time) {
  std::lock_guard lock(mutex_);
  commands_.playing = true;
  commands_.run_until = time;
  wake_.notify_all();
}

void SimulationThread::Loop() {
  Clock::time_point wall_anchor = Clock::now();
  double sim_anchor = 0;
  bool was_playing = false;
  double last_speed = -1;
  // Real-time factor measured over windows of about a second.
  Clock::time_point rate_wall = Clock::now();
  double rate_sim = 0;
  while (!quit_.load()) {
    Commands c;
    {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, std::chrono::milliseconds(20), [&] {
        return quit_.load() || commands_.playing || commands_.steps > 0 || commands_.reset ||
               !commands_.colors.empty() || commands_.tool != 0 || commands_.tool_target_new;
      });
      c = commands_;
      commands_.steps = 0;
      commands_.reset = false;
      commands_.colors.clear();
      commands_.tool = 0;
      commands_.tool_target_new = false;
      status_.playing = commands_.playing;
    }
    if (quit_.load()) break;
    bool republish = false;
    if (c.reset) {
      try {
        Load(display_->Colors());  // the scene's start, drawn as it is drawn now
        UpdateStatus([](SimulationStatus& s) {
          s.failed = false;
          s.at_end = false;
          s.message.clear();
        });
      } catch (const std::exception& e) {
        Report(e.what(), false);
      }
      republish = true;
      was_playing = false;
    }
    for (auto& [surface, spec] : c.colors) {
      if (surface >= display_->size()) continue;
      try {
        DrawSpec draw = display_->manager(surface).draw();
        draw.color = spec;
        DisplayManager& manager = display_->manager(surface);
        manager = DisplayManager(manager.object(), draw, manager.name());
        const std::size_t index = surface;  // clang 14 cannot capture a structured binding
        UpdateStatus([&](SimulationStatus& s) { s.draws[index] = draw; });
      } catch (const std::exception& e) {
        Report(e.what(), false);
      }
      republish = true;
    }
    if (c.tool == 1 && c.tool_surface < display_->size()) {
      // The viewer owns the scene (non-const); the display manager only holds it for reading.
      auto& object = const_cast<SimObject&>(display_->manager(c.tool_surface).geometry_object());
      std::string why;
      if (!LocalModels(*registry_).Contains(object.type_name())) {
        why = fmt::format("object '{}' ({}) cannot be pulled: no haptic local model for its type",
                          object.name(), object.type_name());
      } else {
        try {
          const JsonNode where(nlohmann::ordered_json(), "viewer", "mouse pull");
          why = tool_.Grab(LocalModels(*registry_).Get(object.type_name(), where)(object, 3),
                           c.tool_point, scene_->kernel->macro_dt());
        } catch (const std::exception& e) {
          why = e.what();
        }
      }
      if (!why.empty()) Report("mouse pull: " + why, false);
    } else if (c.tool == 2) {
      tool_.Release();
    }
    if (c.tool_target_new) tool_.MoveTo(c.tool_target);
    if (c.tool != 0 || c.tool_target_new) republish = true;  // the pull's status

    Kernel& kernel = *scene_->kernel;
    const bool failed = status().failed;
    int steps = failed ? 0 : c.steps;
    const bool playing = c.playing && !failed;
    if (playing && (!was_playing || c.speed != last_speed)) {
      wall_anchor = Clock::now();
      sim_anchor = kernel.time();
    }
    was_playing = playing;
    last_speed = c.speed;
    if (playing) {
      const PlayStep next = NextPlayStep(kernel.time(), scene_->end_time, kernel.macro_dt(),
                                         c.at_end, c.run_until >= 0);
      if (next == PlayStep::kPause) {
        std::lock_guard lock(mutex_);
        commands_.playing = false;
        status_.at_end = true;
        continue;
      }
      if (next == PlayStep::kRestart) {
        try {
          Load(display_->Colors());
        } catch (const std::exception& e) {
          Report(e.what(), true);
        }
        Publish();
        was_playing = false;
        continue;
      }
    }
    if (playing) {
      if (c.speed > 0) {  // real-time pacing: do not get ahead of the wall clock
        const double wall = std::chrono::duration<double>(Clock::now() - wall_anchor).count();
        const double ahead = (kernel.time() - sim_anchor) / c.speed - wall;
        if (ahead > 0) {
          std::this_thread::sleep_for(std::chrono::duration<double>(std::min(ahead, 0.01)));
          if (republish) Publish();
          continue;
        }
      }
      steps = 1;
    }
    for (int k = 0; k < steps; ++k) {
      tool_.Apply();  // the pull's spring force for this macro step
      const RunResult result = kernel.Run(kernel.time() + kernel.macro_dt());
      if (!result.ok()) {
        Report(result.diagnostic, true);
        std::lock_guard lock(mutex_);
        commands_.playing = false;
        break;
      }
    }
    if (steps > 0) {
      republish = true;
      UpdateStatus([](SimulationStatus& s) { s.at_end = false; });  // on past the end
    }
    if (c.run_until >= 0 && kernel.time() >= c.run_until - 1e-12) {
      std::lock_guard lock(mutex_);
      commands_.playing = false;
      commands_.run_until = -1;
    }
    const auto now = Clock::now();
    const double window = std::chrono::duration<double>(now - rate_wall).count();
    if (window > 1.0 || !playing) {
      const double rtf = playing && window > 0 ? (kernel.time() - rate_sim) / window : 0;
      rate_wall = now;
      rate_sim = kernel.time();
      UpdateStatus([&](SimulationStatus& s) { s.real_time_factor = rtf; });
    }
    UpdateStatus([&](SimulationStatus& s) {
      s.time = kernel.time();
      s.pull_object = tool_.active() ? kernel.ObjectPath(tool_.object()) : std::string();
      s.pull_force = tool_.force().norm();
      s.pull_max_force = tool_.spring().max_force;
    });
    if (republish) Publish();
  }
}

}  // namespace gipsi::viz
