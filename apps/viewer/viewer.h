#pragma once
/// @file
/// `gipsi view`: the interactive viewer. A desktop window (GLFW, OpenGL 3.3 core, Dear ImGui
/// panels) draws the frames a `SimulationThread` publishes: orbit/pan/zoom camera, play /
/// pause / step / reset, speed, per-object visibility, wireframe, colour field and map with a
/// legend, live probe plots, and the mouse as a tool that pulls the tissue.

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gipsi/viz/camera.h"
#include "gipsi/viz/display_manager.h"
#include "gipsi/viz/playback.h"

namespace gipsi::viz {

/// Options of `gipsi view`. Plain struct.
struct ViewerOptions {
  std::string scene;
  std::vector<std::string> plugins;
  std::vector<std::pair<std::string, ColorSpec>> colors;
  std::vector<std::string> show, hide;  ///< objects to show or hide at first (scene: "visible")
  std::vector<std::string> as;          ///< "OBJECT:lines" etc.: geometry whatever the scene says
  Camera camera;
  int width = 1280, height = 800;
  bool play = false;             ///< start playing
  double speed = 1.0;            ///< target real-time factor (0: as fast as possible)
  AtEnd at_end = AtEnd::kPause;  ///< what playing does at the scene's schedule.end
  bool show_ui = true;           ///< the ImGui panel
  /// Test and batch mode: run to `screenshot_time`, save the window to this PNG, and exit.
  std::string screenshot;
  double screenshot_time = 0;
  /// With a screenshot: at t = 0, Ctrl + left drag from window pixel (x0, y0) to (x1, y1) and
  /// hold it while running to the screenshot time (tests the mouse tool end to end).
  std::optional<std::array<double, 4>> drag;
};

/// Exit code when no window can be opened (no display).
inline constexpr int kNoDisplayExitCode = 5;

/// Runs the viewer until its window is closed (or the screenshot is written); returns the exit
/// code. Throws InputError for a bad scene or colour choice (before any window opens).
int RunViewer(const ViewerOptions& options);

}  // namespace gipsi::viz
