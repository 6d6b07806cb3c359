#pragma once
/// @file
/// `SimulationThread`: runs a scene's kernel on its own thread for the viewer — play, pause,
/// single step, reset (reload), real-time pacing — and publishes display frames (and recent
/// probe samples) through a triple buffer after every macro step. The window thread only sends
/// commands and reads published frames; neither waits for the other except for a short mutex
/// around the command and status structs.

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "gipsi/base/latest_value.h"
#include "gipsi/haptics/haptic_probe.h"
#include "gipsi/haptics/mouse_device.h"
#include "gipsi/haptics/realtime_haptics.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/display_manager.h"
#include "gipsi/viz/mouse_tool.h"
#include "gipsi/viz/playback.h"

namespace gipsi::viz {

/// One drawn object as the panel offers it. Plain struct.
struct DrawnObject {
  std::string name;                 ///< the object's full (dotted) name
  std::vector<std::string> fields;  ///< fields it can be coloured by
  std::vector<int> components;      ///< each field's number of components (1: a scalar)
  /// The mouse can pull it: it has a free boundary, an `external_force` node field and a
  /// haptic local model (LocalModels, gipsi/core/local_model.h) to scale the pull's spring.
  bool pullable = false;
};

/// What the window shows about the simulation. Plain struct.
struct SimulationStatus {
  double time = 0, end_time = 0, macro_dt = 0;
  double real_time_factor = 0;  ///< simulated / wall seconds over the last second of play
  bool playing = false;
  bool at_end = false;  ///< paused at schedule.end
  bool failed = false;
  std::string message;  ///< why it stopped (divergence, reload error), or ""
  /// Per display surface (in frame order): the object's name, the fields it can be coloured by,
  /// and whether the mouse can pull it.
  std::vector<DrawnObject> objects;
  /// Per display surface: how it is drawn and coloured now.
  std::vector<DrawSpec> draws;
  /// The scene has a haptic tool the mouse moves (a HapticProbe with a Mouse device).
  bool haptic_mouse = false;
  /// The mouse pull: the object it holds ("" when none), the force it applies now and its cap
  /// [N].
  std::string pull_object;
  double pull_force = 0, pull_max_force = 0;
};

/// Owns the scene while it runs. Not copyable or movable.
class SimulationThread {
 public:
  /// Loads the scene with the types of the registry it is given (a new one for every load; kept
  /// with the scene, for the mouse pull's local models).
  using LoadFn = std::function<Scene(TypeRegistry&)>;
  /// Loads the scene with `load` on the calling thread (so load errors reach the caller as
  /// exceptions), publishes the initial frame and starts the thread, paused.
  /// `show` and `hide` name objects to show or hide at first (ApplyVisibility); throws
  /// InputError for a name that is not drawn.
  SimulationThread(LoadFn load, std::vector<std::pair<std::string, ColorSpec>> colors,
                   LatestValue<FrameBuffers>& frames, const std::vector<std::string>& show = {},
                   const std::vector<std::string>& hide = {});
  ~SimulationThread();
  SimulationThread(const SimulationThread&) = delete;
  SimulationThread& operator=(const SimulationThread&) = delete;

  void SetPlaying(bool playing);
  /// One macro step (pauses).
  void Step();
  /// Reloads the scene (back to its start), paused.
  void Reset();
  /// Target simulated seconds per wall second while playing; 0 = as fast as possible.
  void SetSpeed(double real_time_factor);
  /// What playing does at the scene's schedule.end (default: pause there).
  void SetAtEnd(AtEnd at_end);
  /// Recolours display surface `surface` (applied between steps, then republished).
  void SetColor(std::size_t surface, ColorSpec spec);
  /// Mouse pull (PullTool): attach a bounded spring to the nearest free boundary node of surface
  /// `surface`'s object at `point`, pull it towards `target`, let go.
  void Grab(std::size_t surface, const Vec3& point);
  void Drag(const Vec3& target);
  void ReleaseTool();
  /// Runs (playing) until the simulated time reaches `time`, then pauses.
  void RunUntil(double time);
  /// The scene's mouse-moved haptic tool (the first HapticProbe with a Mouse device), from the
  /// window thread: MouseDevice's GUI-side calls, made under the mutex so that a reset cannot
  /// take the device away during one. Each does nothing when the scene has no such tool.
  void HapticBeginDrag(const Vec3& view_direction);
  void HapticDragTo(const Vec3& origin, const Vec3& direction);
  void HapticEndDrag();
  void HapticPush(const Vec3& view_direction, double notches);
  /// The tool's position [m] and the force last commanded to it [N], if there is a tool.
  [[nodiscard]] std::optional<std::pair<Vec3, Vec3>> HapticTool();

  [[nodiscard]] SimulationStatus status() const;
  /// Per display surface: hidden at first (the scene's "visible", then --show and --hide).
  [[nodiscard]] const std::vector<bool>& initially_hidden() const { return initially_hidden_; }

 private:
  struct Commands {
    bool playing = false;
    int steps = 0;
    bool reset = false;
    double speed = 1.0;
    AtEnd at_end = AtEnd::kPause;
    double run_until = -1;
    std::vector<std::pair<std::size_t, ColorSpec>> colors;
    // mouse tool
    int tool = 0;  // 0 nothing, 1 grab, 2 release
    std::size_t tool_surface = 0;
    Vec3 tool_point = Vec3::Zero(), tool_target = Vec3::Zero();
    bool tool_target_new = false;
  };
  void Loop();
  /// Loads the scene (again), drawing its objects with `colors` (by full object name).
  void Load(const std::vector<std::pair<std::string, ColorSpec>>& colors);
  void Publish();
  void UpdateStatus(const std::function<void(SimulationStatus&)>& change);
  /// Shows `message` in the panel and writes it to stderr as "gipsi: error: ...".
  void Report(const std::string& message, bool failed);

  LoadFn load_;
  std::vector<std::pair<std::string, ColorSpec>> initial_colors_;
  LatestValue<FrameBuffers>& frames_;
  std::unique_ptr<TypeRegistry> registry_;  // the scene's types (plugins stay loaded)
  std::unique_ptr<Scene> scene_;
  std::unique_ptr<RealtimeHaptics> haptics_;  // after scene_: destroyed (loops joined) first
  std::unique_ptr<SceneDisplay> display_;
  std::vector<ProbeTrace> traces_;
  std::vector<std::size_t> trace_probes_;  // the probe of each trace (line probes have none)
  std::vector<double> sample_;
  std::vector<bool> initially_hidden_;
  PullTool tool_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  Commands commands_;
  SimulationStatus status_;
  MouseDevice* mouse_ = nullptr;  // in scene_; guarded by mutex_
  std::atomic<bool> quit_{false};
  std::thread thread_;
};

}  // namespace gipsi::viz
