#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "apps/cli_test_util.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/display_manager.h"
#include "gipsi/viz/render/offscreen.h"
#include "test_paths.h"

namespace gipsi::viz {
namespace {

using ::testing::HasSubstr;

/// A unit-cube FEM block at rest (nothing moves at t = 0).
constexpr const char* kBlockScene = R"({
  "meshes": {"block": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [2, 2, 2]}},
  "objects": {"block": {"type": "FemSolid", "domain": "block", "dt": 0.01, "density": 1000,
    "material": {"law": "Corotational", "youngs_modulus": 1e5, "poisson_ratio": 0.3},
    "integrator": "BackwardEuler"}},
  "schedule": {"end": 0.01}
})";

Scene LoadBlock(TypeRegistry& registry) {
  RegisterBuiltins(registry);
  return LoadSceneFromString(kBlockScene, "block.json", ".", registry);
}

/// Draws `scene` at its current time as its "display" keys say (colours replaced by `colors`),
/// as `gipsi snapshot` does after running it.
Image RenderScene(const Scene& scene, FrameImageOptions options,
                  const std::vector<std::pair<std::string, ColorSpec>>& colors = {}) {
  SceneDisplay display(*scene.kernel, scene.display, colors);
  FrameBuffers frame;
  display.Fill(scene.kernel->time(), frame);
  options.render.hidden = display.Hidden();
  try {
    return RenderFrame(frame, options);
  } catch (const std::runtime_error& e) {
    ADD_FAILURE() << "off-screen rendering (OSMesa) is unavailable: " << e.what();
    return {};
  }
}

/// Renders the block head-on: the eye on the -y side at the height of the block's centre, so
/// the face y = 0 hides the rest of the block and is seen exactly face-on.
Image RenderHeadOn(FrameImageOptions options,
                   const std::vector<std::pair<std::string, ColorSpec>>& colors = {}) {
  TypeRegistry registry;
  Scene scene = LoadBlock(registry);
  options.camera.azimuth = 0;
  options.camera.elevation = 0;
  options.labels = false;  // text would count as object pixels
  return RenderScene(scene, options, colors);
}

bool IsBackground(const Rgb& c) { return c.r == 1.0f && c.g == 1.0f && c.b == 1.0f; }

TEST(Snapshot, DrawsTheFaceOnBlockAsASquareOfItsColourOnTheBackground) {
  FrameImageOptions options;
  options.width = 240;
  options.height = 180;
  options.supersample = 1;
  const Image image = RenderHeadOn(options);
  ASSERT_EQ(image.width, 240);
  ASSERT_EQ(image.height, 180);
  // The face is seen head-on (n · view = 1), so it shows its solid colour unshaded; 8-bit
  // rounding allows half a level.
  const Rgb centre = image.At(120, 90);
  const Rgb solid = ColorSpec{}.solid;
  EXPECT_NEAR(centre.r, solid.r, 0.5 / 255 + 1e-6);
  EXPECT_NEAR(centre.g, solid.g, 0.5 / 255 + 1e-6);
  EXPECT_NEAR(centre.b, solid.b, 0.5 / 255 + 1e-6);
  for (auto [x, y] : {std::pair{0, 0}, {239, 0}, {0, 179}, {239, 179}, {5, 90}, {120, 5}})
    EXPECT_TRUE(IsBackground(image.At(x, y))) << x << ", " << y;

  // Analytic size: the fitted camera puts the corners of the near face at 1/1.1 of the
  // half-height (the far face's project smaller, inside it); so the face spans H / 1.1 pixels.
  const double side = 180.0 / 1.1;
  int object = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) object += !IsBackground(image.At(x, y));
  // Rasterisation decides the edge pixels: allow one pixel row around the perimeter.
  EXPECT_NEAR(object, side * side, 4 * side + 4) << "square side " << side << " px";
}

TEST(Snapshot, ColoursFollowTheFieldAcrossTheFace) {
  FrameImageOptions options;
  options.width = 240;
  options.height = 180;
  options.supersample = 1;
  ColorSpec spec;
  spec.field = "position";
  spec.component = 0;  // x: 0 at the left edge of the face, 1 at the right
  spec.color_map = "grey";
  options.render.lighting = false;  // smooth normals dim the face near its edges otherwise
  const Image image = RenderHeadOn(options, {{"block", spec}});
  ASSERT_EQ(image.width, 240);
  // The face's edges on the middle row, found outward from the centre of the scene's part of
  // the image (left of the colour bar's strip).
  const ColorBarLayout bar = LayoutColorBar(240, 180);
  const int centre = bar.strip_x0 / 2;
  int left = centre, right = centre;
  while (left > 0 && !IsBackground(image.At(left - 1, 90))) --left;
  while (right + 1 < image.width && !IsBackground(image.At(right + 1, 90))) ++right;
  ASSERT_LT(left + 20, right);
  // The face is at constant depth, so x and the grey level grow linearly across the screen.
  // Tolerance: one pixel of position (1/width of the face) plus 8-bit rounding.
  const double tolerance = 1.0 / (right - left) + 1.0 / 255;
  for (int x = left + 1; x < right; x += 7) {
    const double expected = (x + 0.5 - left) / (right + 1 - left);
    EXPECT_NEAR(image.At(x, 90).r, expected, tolerance) << "column " << x;
  }
  // The colour bar at the right edge: dark at its bottom, light at its top.
  const int bar_x = (bar.x0 + bar.x1) / 2;
  EXPECT_LT(image.At(bar_x, bar.y1 - 1).r, 0.03);
  EXPECT_GT(image.At(bar_x, bar.y0).r, 0.97);
  EXPECT_TRUE(IsBackground(image.At(bar.x0 - 2, 90)));
}

TEST(Snapshot, IsDeterministic) {
  FrameImageOptions options;
  options.width = 160;
  options.height = 120;
  options.camera.azimuth = -60;
  const Image a = RenderHeadOn(options);
  const Image b = RenderHeadOn(options);
  EXPECT_FALSE(a.rgb.empty());
  EXPECT_EQ(a.rgb, b.rgb);
}

TEST(SnapshotCommand, WritesThePngAndReportsTheColourRange) {
  const auto dir = testing::TempDir("gipsi_snapshot_", "cli");
  { std::ofstream(dir / "block.json") << kBlockScene; }
  const auto result = testing::Gipsi(
      fmt::format("snapshot {} --out {} --size 200x100 --color block:position.z --map cool-warm",
                  (dir / "block.json").string(), (dir / "block.png").string()));
  ASSERT_EQ(result.code, 0) << result.output;
  EXPECT_THAT(result.output, HasSubstr("200 x 100 at t = 0 s"));
  EXPECT_THAT(result.output, HasSubstr("block: position z [m] from 0 to 1 (cool-warm)"));
  const Image image = ReadPng(dir / "block.png");
  EXPECT_EQ(image.width, 200);
  EXPECT_EQ(image.height, 100);
  EXPECT_TRUE(IsBackground(image.At(0, 0)));
  EXPECT_FALSE(IsBackground(image.At(60, 50)));
  // The time label "t = 0 s" in the bottom-left corner: dark text pixels.
  int dark = 0;
  for (int y = 70; y < 100; ++y)
    for (int x = 0; x < 60; ++x) dark += image.At(x, y).r < 0.5f;
  EXPECT_GT(dark, 10);
}

TEST(SnapshotCommand, RejectsBadOptionsNamingThem) {
  const std::string scene = std::string(GIPSI_SOURCE_DIR) + "/scenes/cantilever.json";
  auto run = [&](const std::string& args) {
    return testing::Gipsi("snapshot " + scene + " --out /tmp/gipsi_never.png " + args);
  };
  auto r = run("--camera 10");
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.output, HasSubstr("--camera: expected AZIMUTH,ELEVATION[,DISTANCE]"));
  r = run("--size 100");
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.output, HasSubstr("--size: expected WIDTHxHEIGHT"));
  r = run("--color beam");
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.output, HasSubstr("--color: expected OBJECT:FIELD[.COMPONENT], got 'beam'"));
  r = run("--color beam:displacment");
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.output, HasSubstr("displacment"));
  r = run("--color beam:displacement --map jet");
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.output, HasSubstr("--map: unknown colour map 'jet'"));
  r = run("--color nobody:displacement");
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.output, HasSubstr("nobody"));
  r = run("--as beam:wires");
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.output, HasSubstr("--as: expected OBJECT:surface, OBJECT:lines or OBJECT:points"));
  r = run("--as nobody:lines");
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.output, HasSubstr("--as: no object named 'nobody'"));
  r = run("--hide bean");
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.output, HasSubstr("--hide: no object named 'bean' (did you mean 'beam'?)"));
}

/// The unit-cube block drawn as the scene's "display" entry asks, head-on (as RenderHeadOn),
/// without labels or colour bar, one sample per pixel (so no edge is blended with the
/// background).
Image RenderBlockAs(const std::string& display, int width, int height) {
  std::string text = kBlockScene;
  const std::string anchor = R"("integrator": "BackwardEuler")";
  text.replace(text.find(anchor), anchor.size(), anchor + R"(, "display": )" + display);
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(text, "block.json", ".", registry);
  FrameImageOptions options;
  options.width = width;
  options.height = height;
  options.supersample = 1;
  options.camera.azimuth = 0;
  options.camera.elevation = 0;
  options.labels = false;
  options.render.color_bar = false;
  return RenderScene(scene, options);
}

bool Near(const Rgb& c, const Rgb& expected) {
  constexpr float kLevel = 0.5f / 255 + 1e-6f;  // 8-bit rounding
  return std::abs(c.r - expected.r) <= kLevel && std::abs(c.g - expected.g) <= kLevel &&
         std::abs(c.b - expected.b) <= kLevel;
}

// Lines are unshaded and not blended: every drawn pixel is exactly the solid colour. Seen
// head-on, the near face's outline is a square of side H / 1.1 around the centre (see the face
// test above), so on the middle row the first drawn pixel from the left is the left edge
// x = 0 at W/2 - H/2.2, within the 3-pixel line width; the interior of the near face's cells
// shows lines of the cells behind and tet diagonals, but the corners outside the square are
// background.
TEST(Snapshot, DrawsMeshEdgesAsLinesInTheirColour) {
  const Rgb red{1, 0, 0};
  const Image image =
      RenderBlockAs(R"({"as": "lines", "size": 3, "color": {"color": [1, 0, 0]}})", 240, 180);
  ASSERT_EQ(image.width, 240);
  int drawn = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const Rgb c = image.At(x, y);
      if (IsBackground(c)) continue;
      ++drawn;
      EXPECT_TRUE(Near(c, red)) << x << ", " << y;
    }
  EXPECT_GT(drawn, 4 * 160);  // at least the near face's outline, 4 sides of 164 px
  int first = 0;
  while (first < image.width && IsBackground(image.At(first, 90))) ++first;
  EXPECT_NEAR(first + 1.5, 120 - 90 / 1.1, 2.0);
  for (auto [x, y] : {std::pair{0, 0}, {239, 0}, {0, 179}, {239, 179}, {20, 90}, {220, 90}})
    EXPECT_TRUE(IsBackground(image.At(x, y))) << x << ", " << y;
}

// Points coloured by x through the grey map over a fixed range [0, 2]: the near face's corner
// node (0, 0, 0) projects to (W/2 - H/2.2, H/2 + H/2.2) and is black; (1, 0, 1) projects to
// (W/2 + H/2.2, H/2 - H/2.2) with grey 0.5; the centre (x = 0.5 on every node behind it) has
// grey 0.25. 8-px points cover their node's pixel and its neighbours.
TEST(Snapshot, DrawsNodesAsPointsInTheirFieldColour) {
  const Image image = RenderBlockAs(
      R"({"as": "points", "size": 8,
          "color": {"field": "position", "component": "x", "map": "grey", "range": [0, 2]}})",
      240, 180);
  ASSERT_EQ(image.width, 240);
  const double half = 90 / 1.1;
  auto at = [&](double x, double y) {
    return image.At(static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y)));
  };
  EXPECT_TRUE(Near(at(120 - half, 90 + half), Rgb{0, 0, 0}));
  EXPECT_TRUE(Near(at(120 + half, 90 - half), Rgb{0.5f, 0.5f, 0.5f}));
  EXPECT_TRUE(Near(at(120, 90), Rgb{0.25f, 0.25f, 0.25f}));
  // Between nodes there is nothing: the middle of the near face's lower-left cell.
  EXPECT_TRUE(IsBackground(at(120 - half / 2, 90 + half / 2)));
  EXPECT_TRUE(IsBackground(image.At(0, 0)));
}

// The scene's "visible": false hides the object in the snapshot; the command line's --show
// brings it back, and --as draws it as points whatever the scene says.
TEST(Snapshot, HonoursTheScenesVisibilityUnlessTheCommandLineOverridesIt) {
  const Image image = RenderBlockAs(R"({"visible": false})", 120, 90);
  ASSERT_EQ(image.width, 120);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) ASSERT_TRUE(IsBackground(image.At(x, y))) << x << y;

  const auto dir = testing::TempDir("gipsi_snapshot_", "show");
  std::string text = kBlockScene;
  const std::string anchor = R"("integrator": "BackwardEuler")";
  text.replace(text.find(anchor), anchor.size(), anchor + R"(, "display": {"visible": false})");
  { std::ofstream(dir / "block.json") << text; }
  const auto result = testing::Gipsi(
      fmt::format("snapshot {} --out {} --size 120x90 --show block --as block:points --camera 0,0",
                  (dir / "block.json").string(), (dir / "block.png").string()));
  ASSERT_EQ(result.code, 0) << result.output;
  const Image shown = ReadPng(dir / "block.png");
  // The near face's centre node, in the solid colour (points are unshaded; the 2x2
  // supersampling averages the point's interior to its exact colour).
  const Rgb centre = shown.At(60, 45), solid = ColorSpec{}.solid;
  EXPECT_NEAR(centre.r, solid.r, 0.5 / 255 + 1e-6);
  EXPECT_NEAR(centre.g, solid.g, 0.5 / 255 + 1e-6);
  // Between nodes: background (points, not the surface).
  EXPECT_TRUE(IsBackground(shown.At(60 - 18, 45 + 18)));
}

}  // namespace
}  // namespace gipsi::viz
