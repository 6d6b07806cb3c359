#pragma once
/// @file
/// The visualization subcommands of the `gipsi` tool: `snapshot` (off-screen image of a scene),
/// `plot` (PNG/SVG plots of probe CSVs), `view` (the interactive viewer),
/// kept apart from gipsi_main.cc so the rendering dependencies stay in one place.

#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "gipsi/viz/display_manager.h"

namespace gipsi::apps {

/// Adds the visualization subcommands to `app` and runs whichever was chosen. Not copyable
/// (CLI11 keeps pointers to the members).
class VizCommands {
 public:
  explicit VizCommands(CLI::App& app);
  VizCommands(const VizCommands&) = delete;
  VizCommands& operator=(const VizCommands&) = delete;

  /// Runs the chosen visualization subcommand and returns its exit code, or std::nullopt if
  /// another subcommand was chosen. Throws InputError (exit 1) and std::exception.
  std::optional<int> Dispatch();

 private:
  int Snapshot();
  int Plot();
  int View();
  [[nodiscard]] std::vector<std::pair<std::string, ColorSpec>> ParseColors() const;

  CLI::App* snapshot_ = nullptr;
  std::string scene_, out_, camera_, size_ = "800x600", map_ = "viridis", range_;
  std::vector<std::string> colors_, plugins_, show_, hide_, as_;
  double time_ = 0;
  bool wireframe_ = false, no_color_bar_ = false, unlit_ = false;

  CLI::App* view_ = nullptr;
  std::string view_size_ = "1280x800", screenshot_, drag_, at_end_ = "pause";
  double screenshot_time_ = 0, speed_ = 1;
  bool play_ = false, no_ui_ = false;

  CLI::App* plot_ = nullptr;
  std::string csv_, plot_out_, plot_x_, plot_by_, title_, plot_size_ = "800x500";
  std::vector<std::string> plot_y_;
};

}  // namespace gipsi::apps
