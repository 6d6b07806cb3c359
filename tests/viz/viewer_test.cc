// The interactive viewer for real: `gipsi view` under Xvfb (Mesa's software OpenGL through
// GLX) runs a known scene on its simulation thread, draws it with its panel, takes a screenshot
// (glReadPixels of the window) and the test checks what it shows.

#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "apps/cli_test_util.h"
#include "gipsi/viz/render/image.h"
#include "test_paths.h"

namespace gipsi::viz {
namespace {

using ::testing::HasSubstr;

bool InCi() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && std::string(ci) == "true";
}

bool HaveXvfbRun() { return std::system("command -v xvfb-run > /dev/null 2>&1") == 0; }

bool IsBackground(const Rgb& c) { return c.r == 1.0f && c.g == 1.0f && c.b == 1.0f; }

constexpr const char* kBlock = R"({
    "meshes": {"block": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [2, 2, 2]}},
    "objects": {"block": {"type": "FemSolid", "domain": "block", "dt": 0.01, "density": 1000,
      "material": {"law": "Corotational", "youngs_modulus": 1e5, "poisson_ratio": 0.3},
      "integrator": "BackwardEuler", "gravity": [0, 0, 0],
      "boundary_conditions": [{"name": "back", "region": {"group": "ymax"}, "fix": true}]}},
    "schedule": {"end": 1},
    "probes": {"energy": {"object": "block", "fields": ["kinetic_energy"]}}
  })";

/// Result of one viewer run under Xvfb: `skip` says why it could not run (no xvfb-run, or no
/// window even under Xvfb).
struct ViewRun {
  int code = -1;
  std::string output, skip;
  Image image;
};

/// Runs `gipsi view SCENE_FILE --screenshot shot.png ARGS` under xvfb-run (a virtual X
/// display; OpenGL from Mesa's software rasteriser through GLX).
ViewRun ViewFileUnderXvfb(const std::string& name, const std::string& scene_file,
                          const std::string& args) {
  ViewRun run;
  if (!HaveXvfbRun()) {
    run.skip = "xvfb-run is not installed (Debian package xvfb)";
    return run;
  }
  const auto dir = gipsi::testing::TempDir("gipsi_view_", name);
  const std::string command = fmt::format(
      "xvfb-run -a -s '-screen 0 1600x1000x24' {}/bin/gipsi view {} --screenshot {} {} 2>&1",
      GIPSI_BINARY_DIR, scene_file, (dir / "shot.png").string(), args);
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return run;
  char buffer[4096];
  while (std::size_t n = fread(buffer, 1, sizeof buffer, pipe)) run.output.append(buffer, n);
  const int status = pclose(pipe);
  run.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (run.code == 5) run.skip = "the viewer cannot create a window under Xvfb: " + run.output;
  if (run.code == 0) run.image = ReadPng(dir / "shot.png");
  return run;
}

/// Runs `gipsi view block.json --camera 0,0 --size 640x480 --screenshot shot.png ARGS` under
/// xvfb-run, with `scene` as block.json.
ViewRun ViewUnderXvfb(const std::string& name, const std::string& args,
                      const std::string& scene = kBlock) {
  const auto dir = gipsi::testing::TempDir("gipsi_view_scene_", name);
  std::ofstream(dir / "block.json") << scene;
  return ViewFileUnderXvfb(name, (dir / "block.json").string(),
                           "--camera 0,0 --size 640x480 " + args);
}

/// Skips the test (fails it in CI, where the viewer must be tested) when the run could not
/// happen.
#define SKIP_WITHOUT_DISPLAY(run)                          \
  if (!(run).skip.empty()) {                               \
    if (InCi()) FAIL() << (run).skip;                      \
    GTEST_SKIP() << (run).skip << ": viewer test skipped"; \
  }

/// The "mouse pull on 'OBJECT': force F N (cap C N)" line of a run: {F, C}; {-1, -1} if absent.
std::pair<double, double> PullForce(const std::string& output, const std::string& object) {
  const auto at = output.find("mouse pull on '" + object + "'");
  double f = -1, cap = -1;
  if (at != std::string::npos)
    (void)std::sscanf(output.c_str() + at + object.size() + 16, ": force %lf N (cap %lf N)", &f,
                      &cap);
  return {f, cap};
}

TEST(Viewer, DrawsAKnownSceneUnderXvfbAndTakesAScreenshot) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the windowed viewer (GLFW, Mesa's GLX) is not run under AddressSanitizer";
#endif
  const ViewRun run = ViewUnderXvfb("screenshot", "--screenshot-time 0.05");
  SKIP_WITHOUT_DISPLAY(run);
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("640 x 480 at t = 0.05 s"));  // the simulation thread ran
  const Image& image = run.image;

  ASSERT_EQ(image.width, 640);
  ASSERT_EQ(image.height, 480);
  // The scene part: background at its corners, the block's face head-on in its middle with its
  // exact solid colour (headlight along the face normal), to 8-bit rounding.
  const int panel = 640 / 3, centre = panel + (640 - panel) / 2;
  for (auto [x, y] : {std::pair{panel + 3, 3}, {636, 3}, {panel + 3, 476}, {636, 476}})
    EXPECT_TRUE(IsBackground(image.At(x, y))) << x << ", " << y;
  // Above the face's top edge (where the mouse-tool test pulls the surface to): background.
  for (int y = 30; y < 40; ++y) EXPECT_TRUE(IsBackground(image.At(centre, y))) << y;
  const Rgb face = image.At(centre, 240);
  EXPECT_NEAR(face.r, 0.80, 1.0 / 255);
  EXPECT_NEAR(face.g, 0.45, 1.0 / 255);
  EXPECT_NEAR(face.b, 0.40, 1.0 / 255);
  // The panel: mostly ImGui's light window grey (0.94), with dark text in it.
  int panel_grey = 0, dark = 0;
  for (int y = 0; y < 480; ++y)
    for (int x = 0; x < panel; ++x) {
      const Rgb c = image.At(x, y);
      panel_grey += c.r == c.g && c.g == c.b && std::abs(c.r * 255 - 240) <= 1;
      dark += c.r < 0.3f;
    }
  EXPECT_GT(panel_grey, panel * 480 / 2);
  EXPECT_GT(dark, 200);
}

TEST(Viewer, TheMousePullsTheSurfaceTowardsTheMouse) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the windowed viewer (GLFW, Mesa's GLX) is not run under AddressSanitizer";
#endif
  // Ctrl + drag from the face's centre (a mesh node) to 210 px above it, held for 0.3 s: the
  // bounded spring pulls the node up (the soft block, held at its back, shears upwards), so the
  // block now covers pixels above its original top edge (y = 45), and the spring's force is not
  // zero and within its cap. (Before, the node was placed exactly under the mouse: a prescribed
  // displacement, which breaks explicit objects; see the hanging liver's tests below.)
  const int panel = 640 / 3, centre = panel + (640 - panel) / 2;
  const ViewRun run = ViewUnderXvfb(
      "drag", fmt::format("--screenshot-time 0.3 --drag {},240,{},30", centre, centre));
  SKIP_WITHOUT_DISPLAY(run);
  ASSERT_EQ(run.code, 0) << run.output;
  const Image& image = run.image;
  int object_above = 0;
  for (int y = 30; y < 40; ++y)
    for (int x = centre - 3; x <= centre + 3; ++x) object_above += !IsBackground(image.At(x, y));
  EXPECT_GT(object_above, 20);
  const auto [force, cap] = PullForce(run.output, "block");
  EXPECT_GT(force, 0) << run.output;
  EXPECT_LE(force, cap * (1 + 1e-9)) << run.output;
}

// The mouse pull never breaks a simulation (issue 22). Each test runs a scene for 10 s of
// simulated time, as fast as it can (--speed 0), holding a scripted Ctrl + drag from t = 0, and
// checks that it got there with the pull still attached and its force under its cap.
// Cost (wall time on the shared 2-core machine): about 32 s per liver run alone, 90 s for the
// heart; under `ctest -j2` with other builds running, 65 s (zero-length), 142 s (two liver
// drags) and 160 s (heart). 10 s of simulated time is what issue 22 asks for; the runs go as
// fast as they can (--speed 0) and stay under ctest's 300 s timeout.

TEST(Viewer, AZeroLengthPullIsANoOpOnTheHangingLiver) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the windowed viewer (GLFW, Mesa's GLX) is not run under AddressSanitizer";
#endif
  // The report: the default window (1280 x 800, panel 340 px), Ctrl + click on the liver at the
  // scene's centre (810, 400) without moving stopped the run with "spring stretched beyond
  // max_stretch".
  const ViewRun run =
      ViewFileUnderXvfb("liver_zero", std::string(GIPSI_SOURCE_DIR) + "/scenes/hanging_liver.json",
                        "--speed 0 --screenshot-time 10 --drag 810,400,810,400");
  SKIP_WITHOUT_DISPLAY(run);
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("at t = 10 s"));
  EXPECT_EQ(PullForce(run.output, "liver").first, 0) << run.output;  // held, but no force
}

TEST(Viewer, APullKeepsTheHangingLiverRunningFor10SimulatedSeconds) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the windowed viewer (GLFW, Mesa's GLX) is not run under AddressSanitizer";
#endif
  // A 280 px drag to the right, and one as far as the window goes, held for 10 s.
  for (const char* drag : {"810,400,1090,400", "810,400,1279,0"}) {
    const ViewRun run = ViewFileUnderXvfb(
        "liver_pull", std::string(GIPSI_SOURCE_DIR) + "/scenes/hanging_liver.json",
        fmt::format("--speed 0 --screenshot-time 10 --drag {}", drag));
    SKIP_WITHOUT_DISPLAY(run);
    ASSERT_EQ(run.code, 0) << drag << ": " << run.output;
    EXPECT_THAT(run.output, HasSubstr("at t = 10 s"));
    const auto [force, cap] = PullForce(run.output, "liver");
    EXPECT_GT(force, 0) << run.output;
    EXPECT_LE(force, cap * (1 + 1e-9)) << run.output;
  }
}

/// The muscle of the heart in `scene` pulled 280 px sideways and held for 10 s (12 beats): the
/// run reaches 10 s and the pull's force stays within its cap.
void ExpectThePullKeepsTheHeartBeating(const std::string& name, const std::string& scene) {
  const ViewRun run = ViewFileUnderXvfb(name, std::string(GIPSI_SOURCE_DIR) + "/scenes/" + scene,
                                        "--speed 0 --screenshot-time 10 --drag 810,400,1090,400");
  SKIP_WITHOUT_DISPLAY(run);
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("at t = 10 s"));
  const auto [force, cap] = PullForce(run.output, "heart.muscle");
  EXPECT_GT(force, 0) << run.output;
  EXPECT_LE(force, cap * (1 + 1e-9)) << run.output;
}

TEST(Viewer, APullKeepsTheHeartBeatingFor10SimulatedSeconds) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the windowed viewer (GLFW, Mesa's GLX) is not run under AddressSanitizer";
#endif
  // The muscle is a FemSolid in the Heart aggregate. The bioelectricity surface on the same
  // tissue is not pulled.
  ExpectThePullKeepsTheHeartBeating("heart_pull", "heart.json");
}

TEST(Viewer, APullKeepsTheMassSpringHeartBeatingFor10SimulatedSeconds) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the windowed viewer (GLFW, Mesa's GLX) is not run under AddressSanitizer";
#endif
  // The muscle is an explicit MassSpring (0.1 ms steps): the bounded spring keeps it stable.
  ExpectThePullKeepsTheHeartBeating("heart_ms_pull", "heart_mass_spring.json");
}

TEST(Viewer, TheMouseMovesAHapticToolIntoTheTissue) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the windowed viewer (GLFW, Mesa's GLX) is not run under AddressSanitizer";
#endif
  // A haptic probe whose device is the mouse, ticking in a real-time loop, starts 5 cm left of
  // the block's left face (x = 0) at the height of its centre. Seen head-on (looking along +y),
  // --drag moves the tool in the plane y = 0.5 facing the viewer to the pick ray of the window's
  // centre: the block's centre (0.5, 0.5, 0.5), the camera's target. There the coupling spring
  // (1000 N/m) stretched over 0.5 m asks for far more than max_force, so the force commanded is
  // clamped to 2 N and points out of the left face (−x, the contact vertex's normal); the
  // staleness limit is raised because the simulation under Xvfb may lag the wall clock.
  std::string scene = kBlock;
  const std::string anchor = R"("schedule")";
  scene.replace(
      scene.find(anchor), anchor.size(),
      R"("connectors": {"haptics": {"type": "HapticCoupling", "object": "block", "device": "probe", "capture_distance": 0.1}},
    "schedule")");
  const std::string objects_end = R"("fix": true}]}},)";
  scene.replace(scene.find(objects_end), objects_end.size(), R"("fix": true}]},
      "probe": {"type": "HapticProbe", "dt": 0.01, "rate": 1000, "coupling_stiffness": 1000,
                "max_force": 2, "stale_after": 10, "realtime": true,
                "device": {"type": "Mouse", "start": [-0.05, 0.5, 0.5]}}},)");
  const ViewRun run =
      ViewUnderXvfb("haptic", "--no-ui --screenshot-time 0.2 --drag 320,240,320,240", scene);
  SKIP_WITHOUT_DISPLAY(run);
  ASSERT_EQ(run.code, 0) << run.output;
  double x[3], f[3];
  const auto at = run.output.find("haptic tool at");
  ASSERT_NE(at, std::string::npos) << run.output;
  ASSERT_EQ(std::sscanf(run.output.c_str() + at,
                        "haptic tool at (%lf, %lf, %lf) m, force (%lf, %lf, %lf) N", &x[0], &x[1],
                        &x[2], &f[0], &f[1], &f[2]),
            6)
      << run.output;
  // The centre pixel's ray is the camera's axis up to float rounding of the view matrices.
  EXPECT_NEAR(x[0], 0.5, 1e-4);
  EXPECT_NEAR(x[1], 0.5, 1e-9);  // on the drag plane (computed in double)
  EXPECT_NEAR(x[2], 0.5, 1e-4);
  EXPECT_NEAR(f[0], -2, 1e-9);  // clamped to max_force, normal to the left face
  EXPECT_NEAR(f[1], 0, 1e-9);
  EXPECT_NEAR(f[2], 0, 1e-9);
}

TEST(Viewer, DrawsTheHapticToolAsABlackPointWhileItFeelsNothing) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the windowed viewer (GLFW, Mesa's GLX) is not run under AddressSanitizer";
#endif
  // The mouse tool rests 0.1 m in front of the near face's centre, on the camera's axis (the
  // window's centre without the panel), outside the block: a 12-pixel black point (points are
  // unshaded, so exactly black) over the block's face, which shows around it.
  std::string scene = kBlock;
  const std::string objects_end = R"("fix": true}]}},)";
  scene.replace(scene.find(objects_end), objects_end.size(), R"("fix": true}]},
      "probe": {"type": "HapticProbe", "dt": 0.01, "realtime": true,
                "device": {"type": "Mouse", "start": [0.5, -0.1, 0.5]}}},)");
  const ViewRun run = ViewUnderXvfb("tool", "--no-ui --screenshot-time 0.05", scene);
  SKIP_WITHOUT_DISPLAY(run);
  ASSERT_EQ(run.code, 0) << run.output;
  const Image& image = run.image;
  for (int dy = -3; dy <= 3; ++dy)
    for (int dx = -3; dx <= 3; ++dx) {
      const Rgb c = image.At(320 + dx, 240 + dy);
      EXPECT_TRUE(c.r == 0 && c.g == 0 && c.b == 0) << dx << ", " << dy;
    }
  const Rgb face = image.At(320 + 30, 240);
  EXPECT_FALSE(IsBackground(face));
  EXPECT_GT(face.r, 0.3f);  // the block's colour, not the point's
}

// The scene asks for the block's mesh edges as 3-pixel red lines (unshaded, so every drawn
// pixel is exactly red; the viewer has no multisampling). Without the panel the scene fills the
// window; seen head-on the near face's outline is a square of side H / 1.1 around the centre, so
// on the middle row the first drawn pixel from the left is its left edge at W/2 - H/2.2.
TEST(Viewer, DrawsTheScenesLinesInTheirColour) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the windowed viewer (GLFW, Mesa's GLX) is not run under AddressSanitizer";
#endif
  std::string scene = kBlock;
  const std::string anchor = R"("integrator": "BackwardEuler")";
  scene.replace(
      scene.find(anchor), anchor.size(),
      anchor + R"(, "display": {"as": "lines", "size": 3, "color": {"color": [1, 0, 0]}})");
  const ViewRun run = ViewUnderXvfb("lines", "--no-ui --screenshot-time 0", scene);
  SKIP_WITHOUT_DISPLAY(run);
  ASSERT_EQ(run.code, 0) << run.output;
  const Image& image = run.image;
  ASSERT_EQ(image.width, 640);
  int red = 0, other = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const Rgb c = image.At(x, y);
      if (IsBackground(c)) continue;
      const bool exact = c.r == 1.0f && c.g == 0.0f && c.b == 0.0f;
      red += exact;
      other += !exact;
    }
  EXPECT_GT(red, 4 * 400);  // at least the outline: 4 sides of 436 px, 3 px wide
  EXPECT_EQ(other, 0);
  int first = 0;
  while (first < image.width && IsBackground(image.At(first, 240))) ++first;
  EXPECT_NEAR(first + 1.5, 320 - 240 / 1.1, 2.0);
}

TEST(Viewer, SaysSoWhenThereIsNoDisplay) {
  const auto result = gipsi::testing::Gipsi("view " + std::string(GIPSI_SOURCE_DIR) +
                                            "/scenes/cantilever.json --screenshot /dev/null");
  if (std::getenv("DISPLAY") != nullptr || std::getenv("WAYLAND_DISPLAY") != nullptr)
    GTEST_SKIP() << "a display is available here";
  EXPECT_EQ(result.code, 5) << result.output;
  EXPECT_THAT(result.output, HasSubstr("cannot open a window"));
  EXPECT_THAT(result.output, HasSubstr("xvfb-run"));
}

}  // namespace
}  // namespace gipsi::viz
