#include "viz_commands.h"

#include <charconv>
#include <iostream>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/builtins.h"
#include "gipsi/viz/render/offscreen.h"

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

}  // namespace

VizCommands::VizCommands(CLI::App& app) {
  snapshot_ = app.add_subcommand(
      "snapshot", "Render a scene off screen (no window or display needed) to a PNG image");
  snapshot_->add_option("SCENE", scene_, "Scene file (JSON)")->required();
  snapshot_->add_option("-o,--out", out_, "PNG file to write")->required();
  snapshot_->add_option("-t,--time", time_, "Simulated time to run to first [s] (0: initial state)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
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
  snapshot_->add_flag("--unlit", unlit_,
                      "No shading: every pixel shows its exact colour-map colour");
  snapshot_->add_flag("--no-color-bar", no_color_bar_, "Do not draw the colour bar");
  snapshot_->add_option("--plugin", plugins_, "Load a plugin shared library (repeatable)");
}

std::optional<int> VizCommands::Dispatch() {
  if (*snapshot_) return Snapshot();
  return std::nullopt;
}

int VizCommands::Snapshot() {
  viz::SnapshotOptions options;
  const auto [w, h] = ParsePair(size_, 'x', "--size", "WIDTHxHEIGHT, e.g. 800x600");
  if (!(w >= 16 && h >= 16 && w <= 8192 && h <= 8192 && w == int(w) && h == int(h)))
    ThrowInputError("command line", "--size",
                    fmt::format("expected whole numbers of pixels in [16, 8192], got '{}'", size_));
  options.width = int(w);
  options.height = int(h);
  options.time = time_;
  if (!camera_.empty()) viz::ParseCamera(camera_, "--camera", options.camera);
  std::optional<std::pair<double, double>> range;
  if (!range_.empty()) {
    range = ParsePair(range_, ',', "--range", "LO,HI");
    if (!(range->second > range->first))
      ThrowInputError("command line", "--range", fmt::format("expected LO < HI, got '{}'", range_));
  }
  for (const auto& c : colors_)
    options.colors.push_back(viz::ParseColorOption(c, map_, range, "--color"));
  options.render.wireframe = wireframe_;
  options.render.color_bar = !no_color_bar_;
  options.render.lighting = !unlit_;

  TypeRegistry registry;
  RegisterBuiltins(registry);
  for (const auto& plugin : plugins_) registry.LoadPlugin(plugin);
  Scene scene = LoadScene(scene_, registry);
  viz::SnapshotResult result;
  const viz::Image image = viz::RenderSnapshot(scene, options, &result);
  if (!result.run_ok) {
    std::cerr << "gipsi: error: " << result.diagnostic << "\n";
    return 3;
  }
  try {
    viz::WritePng(image, out_);
  } catch (const std::exception& e) {
    std::cerr << "gipsi: error: " << e.what() << "\n";
    return 4;
  }
  std::cout << fmt::format("{}: {} x {} at t = {:.6g} s ({})\n", out_, image.width, image.height,
                           result.time, result.gl);
  for (const auto& s : result.frame.surfaces)
    if (!s.field.empty())
      std::cout << fmt::format("  {}: {} [{}] from {:.6g} to {:.6g} ({})\n", s.object, s.field,
                               s.units, s.range_lo, s.range_hi, s.color_map);
  return 0;
}

}  // namespace gipsi::apps
