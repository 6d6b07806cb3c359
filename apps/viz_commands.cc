#include "viz_commands.h"

#include "cli_checks.h"

#include <charconv>
#include <iostream>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/haptics/realtime_haptics.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/csv_table.h"
#include "gipsi/viz/display_manager.h"
#include "gipsi/viz/render/offscreen.h"
#include "gipsi/viz/render/plot.h"
#include "viewer/viewer.h"

namespace gipsi::apps {
namespace {

/// "A<sep>B" as two numbers; throws InputError naming `option`.
std::pair<double, double> ParsePair(const std::string& text, char sep, std::string_view option,
                                    std::string_view expected) {
  const std::size_t at = text.find(sep);
  double a = 0, b = 0;
  bool ok = at != std::string::npos;
  if (ok) {
    const char* end = text.data() + text.size();
    auto r1 = std::from_chars(text.data(), text.data() + at, a);
    auto r2 = std::from_chars(text.data() + at + 1, end, b);
    ok =
        r1.ec == std::errc() && r1.ptr == text.data() + at && r2.ec == std::errc() && r2.ptr == end;
  }
  if (!ok)
    ThrowInputError("command line", option, fmt::format("expected {}, got '{}'", expected, text));
  return {a, b};
}

/// "WIDTHxHEIGHT" in [min, 8192] pixels; throws InputError naming --size.
std::pair<int, int> ParseSize(const std::string& text, int min) {
  const auto [w, h] = ParsePair(text, 'x', "--size", "WIDTHxHEIGHT, e.g. 800x600");
  if (!(w >= min && h >= min && w <= 8192 && h <= 8192 && w == int(w) && h == int(h)))
    ThrowInputError(
        "command line", "--size",
        fmt::format("expected whole numbers of pixels in [{}, 8192], got '{}'", min, text));
  return {int(w), int(h)};
}

}  // namespace

VizCommands::VizCommands(CLI::App& app) {
  snapshot_ = app.add_subcommand(
      "snapshot", "Render a scene off screen (no window or display needed) to a PNG image");
  snapshot_->add_option("SCENE", scene_, "Scene file (JSON)")->required();
  snapshot_->add_option("-o,--out", out_, "PNG file to write")->required();
  snapshot_->add_option("-t,--time", time_, "Simulated time to run to first [s] (0: initial state)")
      ->capture_default_str()
      ->check(NonNegativeNumber("a non-negative number of seconds"));
  snapshot_->add_option("--camera", camera_,
                        "AZIMUTH,ELEVATION[,DISTANCE]: degrees about +z (0 = from -y), degrees "
                        "above the xy plane, scene units (default -60,25 and fitted distance)");
  snapshot_->add_option("--size", size_, "Image size WIDTHxHEIGHT in pixels")
      ->capture_default_str();
  snapshot_->add_option("--color", colors_,
                        "Colour OBJECT by FIELD: OBJECT:FIELD[.x|.y|.z] (repeatable; default: "
                        "solid colours)");
  snapshot_->add_option("--map", map_, "Colour map: viridis, cool-warm, grey, rainbow")
      ->capture_default_str();
  snapshot_->add_option("--range", range_, "Fixed colour range LO,HI (default: the values')");
  snapshot_->add_flag("--wireframe", wireframe_, "Draw triangle edges");
  snapshot_->add_option("--as", as_,
                        "Draw OBJECT:surface, OBJECT:lines (springs or mesh edges) or "
                        "OBJECT:points (nodes) whatever the scene says (repeatable)");
  snapshot_->add_option("--show", show_, "Draw OBJECT even if the scene hides it (repeatable)");
  snapshot_->add_option("--hide", hide_, "Do not draw OBJECT (repeatable)");
  snapshot_->add_flag("--unlit", unlit_,
                      "No shading: every pixel shows its exact colour-map colour");
  snapshot_->add_flag("--no-color-bar", no_color_bar_, "Do not draw the colour bar");
  snapshot_->add_option("--plugin", plugins_, "Load a plugin shared library (repeatable)");

  view_ = app.add_subcommand(
      "view",
      "Open a window that runs the scene interactively (play, pause, step, reset, "
      "camera, colours, live probe plots, the mouse as a tool)");
  view_->add_option("SCENE", scene_, "Scene file (JSON)")->required();
  view_->add_option("--camera", camera_, "AZIMUTH,ELEVATION[,DISTANCE], as for snapshot");
  view_->add_option("--size", view_size_, "Window size WIDTHxHEIGHT")->capture_default_str();
  view_->add_option("--color", colors_, "Colour OBJECT by FIELD: OBJECT:FIELD[.x|.y|.z]");
  view_->add_option("--map", map_, "Colour map for --color")->capture_default_str();
  view_->add_option("--range", range_, "Fixed colour range LO,HI for --color");
  view_->add_option("--as", as_, "OBJECT:surface|lines|points, as for snapshot");
  view_->add_option("--show", show_, "Show OBJECT at first even if the scene hides it");
  view_->add_option("--hide", hide_, "Hide OBJECT at first (repeatable)");
  view_->add_flag("--play", play_, "Start playing");
  view_->add_option("--speed", speed_, "Target real-time factor (0: as fast as possible)")
      ->capture_default_str()
      ->check(NonNegativeNumber("a non-negative real-time factor"));
  view_
      ->add_option("--at-end", at_end_,
                   "At the scene's schedule.end while playing: pause, loop (start again) or "
                   "continue")
      ->capture_default_str();
  view_->add_flag("--no-ui", no_ui_, "Hide the panel");
  view_->add_option("--screenshot", screenshot_,
                    "Run to --screenshot-time, save the window as this PNG and exit");
  view_->add_option("--screenshot-time", screenshot_time_, "Simulated time of the screenshot [s]")
      ->capture_default_str()
      ->check(NonNegativeNumber("a non-negative number of seconds"));
  view_->add_option("--drag", drag_,
                    "With --screenshot: X0,Y0,X1,Y1: at t = 0 pull the surface under window "
                    "pixel (X0, Y0) to (X1, Y1) with the mouse tool and hold it (for tests)");
  view_->add_option("--plugin", plugins_, "Load a plugin shared library (repeatable)");

  plot_ = app.add_subcommand("plot",
                             "Plot columns of a CSV file (e.g. a probe's) as a PNG or SVG image: "
                             "traces over time, or one column against another (a PV loop)");
  plot_->add_option("CSV", csv_, "CSV file with a header row, e.g. out/SCENE/probes/tip.csv")
      ->required();
  plot_->add_option("-o,--out", plot_out_, "Image to write: .png or .svg")->required();
  plot_->add_option("--x", plot_x_,
                    "Column on the horizontal axis (default: time; for a line probe's CSV, "
                    "distance)");
  plot_->add_option("--by", plot_by_,
                    "One curve per run of equal values of this column (default: for a line "
                    "probe's CSV, time: one profile per sample time)");
  plot_->add_option("--y", plot_y_, "Column to plot (repeatable; default: every other column)");
  plot_->add_option("--title", title_, "Title above the plot");
  plot_->add_option("--size", plot_size_, "Image size WIDTHxHEIGHT in pixels")
      ->capture_default_str();
}

std::optional<int> VizCommands::Dispatch() {
  if (*snapshot_) return Snapshot();
  if (*plot_) return Plot();
  if (*view_) return View();
  return std::nullopt;
}

int VizCommands::Plot() {
  const auto [w, h] = ParseSize(plot_size_, 100);
  const viz::CsvTable table = viz::ReadCsv(csv_);
  viz::PlotData data;
  data.title = title_;
  data.width = w;
  data.height = h;
  // A line probe's CSV (time, distance, x, y, z, fields...): profiles along the line.
  const bool line = table.names.size() > 5 && table.names[0] == "time" &&
                    table.names[1] == "distance" && table.names[2] == "x" &&
                    table.names[3] == "y" && table.names[4] == "z";
  const std::string x_name = !plot_x_.empty() ? plot_x_ : line ? "distance" : "time";
  const std::string by = !plot_by_.empty() ? plot_by_ : line && x_name != "time" ? "time" : "";
  data.x_label = x_name == "time" ? "time [s]" : x_name;
  const std::vector<double>& x = table.Column(x_name);
  std::vector<std::string> ys = plot_y_;
  if (ys.empty())
    for (std::size_t c = line ? 5 : 0; c < table.names.size(); ++c)
      if (table.names[c] != x_name && table.names[c] != by) ys.push_back(table.names[c]);
  for (const auto& y : ys) {
    if (by.empty()) {
      data.series.push_back({y, x, table.Column(y)});
    } else {
      for (auto& series : viz::SplitSeries(y, x, table.Column(y), table.Column(by), by))
        data.series.push_back(std::move(series));
    }
  }
  if (ys.size() == 1) data.y_label = ys[0];
  try {
    viz::WritePlot(data, plot_out_);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    std::cerr << "gipsi: error: " << e.what() << "\n";
    return 4;
  }
  std::cout << fmt::format("{}: {} x {}, {} series of {} rows from {}\n", plot_out_, w, h,
                           data.series.size(), table.num_rows(), csv_);
  return 0;
}

int VizCommands::View() {
  viz::ViewerOptions options;
  std::tie(options.width, options.height) = ParseSize(view_size_, 200);
  options.scene = scene_;
  options.plugins = plugins_;
  options.colors = ParseColors();
  options.show = show_;
  options.hide = hide_;
  options.as = as_;
  if (!camera_.empty()) viz::ParseCamera(camera_, "--camera", options.camera);
  options.play = play_;
  options.speed = speed_;
  options.at_end = viz::ParseAtEnd(at_end_, "--at-end");
  options.show_ui = !no_ui_;
  options.screenshot = screenshot_;
  options.screenshot_time = screenshot_time_;
  if (!drag_.empty()) {
    std::array<double, 4> d{};
    std::size_t start = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      const std::size_t comma = k < 3 ? drag_.find(',', start) : drag_.size();
      const char* first = drag_.data() + start;
      const char* last = drag_.data() + std::min(comma, drag_.size());
      const auto [end, error] = std::from_chars(first, last, d[k]);
      if (comma == std::string::npos || error != std::errc() || end != last)
        ThrowInputError("command line", "--drag",
                        fmt::format("expected X0,Y0,X1,Y1 in window pixels, got '{}'", drag_));
      start = comma + 1;
    }
    if (screenshot_.empty())
      ThrowInputError("command line", "--drag", "only works with --screenshot");
    options.drag = d;
  }
  return viz::RunViewer(options);
}

std::vector<std::pair<std::string, ColorSpec>> VizCommands::ParseColors() const {
  std::optional<std::pair<double, double>> range;
  if (!range_.empty()) {
    range = ParsePair(range_, ',', "--range", "LO,HI");
    if (!(range->second > range->first))
      ThrowInputError("command line", "--range", fmt::format("expected LO < HI, got '{}'", range_));
  }
  std::vector<std::pair<std::string, ColorSpec>> colors;
  for (const auto& c : colors_) colors.push_back(ParseColorOption(c, map_, range, "--color"));
  return colors;
}

int VizCommands::Snapshot() {
  viz::FrameImageOptions options;
  std::tie(options.width, options.height) = ParseSize(size_, 16);
  if (!camera_.empty()) viz::ParseCamera(camera_, "--camera", options.camera);
  const auto colors = ParseColors();
  options.render.wireframe = wireframe_;
  options.render.color_bar = !no_color_bar_;
  options.render.lighting = !unlit_;

  TypeRegistry registry;
  RegisterBuiltins(registry);
  for (const auto& plugin : plugins_) registry.LoadPlugin(ResolvePlugin(plugin, "."));
  Scene scene = LoadScene(scene_, registry);
  // Every object as the scene's "display" keys say, with the command line's choices on top;
  // checked before anything runs.
  viz::ApplyGeometryOptions(*scene.kernel, as_, "--as", scene.display);
  viz::SceneDisplay display(*scene.kernel, scene.display, colors);
  options.render.hidden = display.Hidden();
  std::vector<std::string> names;
  for (std::size_t i = 0; i < display.size(); ++i) names.push_back(display.manager(i).name());
  viz::ApplyVisibility(*scene.kernel, names, show_, hide_, options.render.hidden);
  if (time_ > scene.kernel->time()) {
    RealtimeHaptics haptics(*scene.kernel);  // real-time probes tick while it runs
    haptics.Start();
    const RunResult run = scene.kernel->Run(time_);
    haptics.Stop();
    if (!run.ok()) {
      std::cerr << "gipsi: error: " << run.diagnostic << "\n";
      return 3;
    }
  }
  const double time = scene.kernel->time();
  viz::FrameBuffers frame;
  display.Fill(time, frame);
  std::string gl;
  const viz::Image image = viz::RenderFrame(frame, options, &gl);
  try {
    viz::WritePng(image, out_);
  } catch (const std::exception& e) {
    std::cerr << "gipsi: error: " << e.what() << "\n";
    return 4;
  }
  std::cout << fmt::format("{}: {} x {} at t = {:.6g} s ({})\n", out_, image.width, image.height,
                           time, gl);
  for (const auto& s : frame.surfaces)
    if (!s.field.empty())
      std::cout << fmt::format("  {}: {} [{}] from {:.6g} to {:.6g} ({})\n", s.object, s.field,
                               s.units, s.range_lo, s.range_hi, s.color_map);
  return 0;
}

}  // namespace gipsi::apps
