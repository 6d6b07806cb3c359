// Line probes: a field sampled along a straight line at given times (or at the end of a run),
// written as CSV (time, distance, x, y, z, values) and plotted as profiles, e.g. the activation
// time along a slab's diagonal.

#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "apps/cli_test_util.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/outputs.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/csv_table.h"
#include "gipsi/viz/plot_data.h"
#include "gipsi/viz/render/plot.h"
#include "io/scene_test_util.h"

namespace gipsi::viz {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

/// A unit-cube FEM block (2 x 2 x 2 cells of 6 tets) at rest, with `probes` and `plots`.
std::string BlockScene(const std::string& probes, const std::string& plots = "[]") {
  return R"({
    "meshes": {"block": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [2, 2, 2]}},
    "objects": {"block": {"type": "FemSolid", "domain": "block", "dt": 0.01, "density": 1000,
      "material": {"law": "Corotational", "youngs_modulus": 1e5, "poisson_ratio": 0.3},
      "integrator": "BackwardEuler"}},
    "schedule": {"end": 0.02},
    "probes": )" +
         probes + R"(,
    "outputs": {"plots": )" +
         plots + R"(}
  })";
}

/// Loads `text`, records its outputs under a fresh directory and runs it to its end.
std::filesystem::path RunScene(const std::string& text, const std::string& name) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(text, name + ".json", ".", registry);
  const auto dir = testing::TempDir("gipsi_line_probe_", name);
  scene.vtu.enabled = false;
  AttachOutputs(scene, dir);
  const RunResult result = scene.kernel->Run(scene.end_time);
  EXPECT_TRUE(result.ok()) << result.diagnostic;
  for (const auto& file : WritePlots(scene.plots, dir))  // as `gipsi run` does at the end
    EXPECT_GT(std::filesystem::file_size(file), 1000u) << file;
  return dir;
}

// Barycentric interpolation in tets reproduces a linear field exactly, so the rest positions
// sampled along a line are the line's own points (to round-off, 1e-12 m on a unit cube); the
// distance column is s |to - from| for s = j / (n - 1).
TEST(LineProbe, ReproducesALinearFieldExactlyAlongTheLine) {
  const auto dir = RunScene(BlockScene(R"({"line": {"object": "block", "fields": ["position"],
      "line": {"from": [0.1, 0.2, 0.3], "to": [0.9, 0.7, 0.65], "points": 9}, "at": 0}})"),
                            "linear");
  const CsvTable table = ReadCsv(dir / "probes" / "line.csv");
  EXPECT_THAT(table.names, ElementsAre("time", "distance", "x", "y", "z", "position_x",
                                       "position_y", "position_z"));
  ASSERT_EQ(table.num_rows(), 9u);  // one sample time ("at": 0), 9 points
  const Vec3 from(0.1, 0.2, 0.3), to(0.9, 0.7, 0.65);
  for (std::size_t j = 0; j < 9; ++j) {
    const double s = double(j) / 8;
    const Vec3 p = (1 - s) * from + s * to;
    EXPECT_EQ(table.Column("time")[j], 0.0);
    EXPECT_NEAR(table.Column("distance")[j], s * (to - from).norm(), 1e-15);
    for (int k = 0; k < 3; ++k) {
      const std::string axis(1, char('x' + k));
      EXPECT_NEAR(table.Column(axis)[j], p[k], 1e-15);
      EXPECT_NEAR(table.Column("position_" + axis)[j], p[k], 1e-12) << "point " << j;
    }
  }
}

TEST(LineProbe, SamplesAtEachRequestedTimeOrOnceAtTheEnd) {
  const auto dir = RunScene(BlockScene(R"({
      "two": {"object": "block", "field": "displacement", "at": [0.005, 0.02],
              "line": {"from": [0, 0, 0], "to": [1, 0, 0], "points": 3}},
      "end": {"object": "block", "field": "displacement",
              "line": {"from": [0, 0, 0], "to": [1, 0, 0], "points": 4}}})",
                                       R"([{"file": "two.png", "y": "two.displacement_z"}])"),
                            "times");
  const CsvTable two = ReadCsv(dir / "probes" / "two.csv");
  // 0.005 s falls inside the first 0.01 s macro step: sampled at the first step reaching it.
  EXPECT_THAT(two.Column("time"), ElementsAre(0.01, 0.01, 0.01, 0.02, 0.02, 0.02));
  const CsvTable end = ReadCsv(dir / "probes" / "end.csv");
  EXPECT_THAT(end.Column("time"), ElementsAre(0.02, 0.02, 0.02, 0.02));
  EXPECT_THAT(end.Column("distance"), ElementsAre(0.0, 1.0 / 3, 2.0 / 3, 1.0));

  // The plot draws one profile per sample time against the distance along the line.
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(
      BlockScene(R"({"two": {"object": "block", "field": "displacement", "at": [0.005, 0.02],
                 "line": {"from": [0, 0, 0], "to": [1, 0, 0], "points": 3}}})",
                 R"([{"file": "two.png", "y": "two.displacement_z"}])"),
      "plot.json", ".", registry);
  ASSERT_EQ(scene.plots.size(), 1u);
  EXPECT_TRUE(scene.plots[0].profile);
  const PlotData data = LoadPlotData(scene.plots[0], dir / "probes");
  ASSERT_EQ(data.series.size(), 2u);
  EXPECT_EQ(data.series[0].label, "displacement z at t = 0.01 s");
  EXPECT_EQ(data.series[1].label, "displacement z at t = 0.02 s");
  EXPECT_THAT(data.series[1].x, ElementsAre(0.0, 0.5, 1.0));
  EXPECT_EQ(data.x_label, "distance [m]");
}

TEST(LineProbe, BadLinesNameTheirJsonPath) {
  auto error = [](const std::string& probe) {
    return testing::SceneLoadError(BlockScene(R"({"p": )" + probe + "}"));
  };
  const std::string line = R"("line": {"from": [0, 0, 0], "to": [1, 1, 1], "points": 5})";
  EXPECT_THAT(error(R"({"object": "block", "field": "position", "line": {"from": [0, 0, 0],
                       "to": [2, 0, 0], "points": 5}})"),
              HasSubstr("scene.json: probes.p.line: the line leaves the domain of 'block'"));
  EXPECT_THAT(error(R"({"object": "block", "field": "position", "line": {"from": [0, 0, 0],
                       "to": [1, 0, 0], "points": 1}})"),
              HasSubstr("probes.p.line.points: expected a number of points in [2, 100000]"));
  EXPECT_THAT(error(R"({"object": "block", "field": "position", "line": {"from": [0, 0, 0],
                       "to": [0, 0, 0], "points": 3}})"),
              HasSubstr("probes.p.line.to: the line has zero length"));
  EXPECT_THAT(error(R"({"object": "block", "field": "kinetic_energy", )" + line + "}"),
              HasSubstr("probes.p.field: line probes interpolate node fields"));
  EXPECT_THAT(error(R"({"object": "block", "field": "position", "every": 0.01, )" + line + "}"),
              HasSubstr("probes.p.every: a line probe samples at the times 'at'"));
  EXPECT_THAT(
      error(R"({"object": "block", "field": "position", "at": [0.01, 0.01], )" + line + "}"),
      HasSubstr("probes.p.at: expected increasing times"));
  EXPECT_THAT(error(R"({"object": "block", "field": "position", "at": 0, "point": [0, 0, 0]})"),
              HasSubstr("probes.p.at: only line probes take sample times"));
  EXPECT_THAT(
      error(R"({"object": "block", "field": "position", "point": [0, 0, 0], )" + line + "}"),
      HasSubstr("probes.p: give one of 'point', 'region' or 'line'"));
  // A plot of a line probe against time makes no sense.
  EXPECT_THAT(testing::SceneLoadError(
                  BlockScene(R"({"p": {"object": "block", "field": "position", )" + line + "}}",
                             R"([{"file": "p.png", "x": "time", "y": "p.position_x"}])")),
              HasSubstr("outputs.plots[0].x: probe 'p' samples along a line"));
}

/// A 40 mm Nagumo bar stimulated at x < 2 mm, run to `end` [s], with a line probe of the
/// activation time from (x0, 0, 0) to (x0 + 16, h, h) mm (33 points) and `more_probes` beside it.
std::string NagumoBar(double end, const std::string& more_probes = "", double x0 = 0.01) {
  return R"({
    "objects": {"bar": {"type": "GridMonodomain", "dt": 5e-6,
      "grid": {"min": [0, 0, 0], "max": [0.04, 0.00025, 0.00025], "cells": [160, 1, 1]},
      "cell": {"model": "Nagumo", "k": 1, "a": 0.25, "v_rest": 0, "v_peak": 1},
      "conductivity": {"longitudinal": 1, "transverse": 1},
      "surface_to_volume": 1000, "capacitance": 1, "fibres": {"direction": [1, 0, 0]},
      "stimuli": {"end": {"region": {"box": {"min": [-1, -1, -1], "max": [0.002, 1, 1]}},
                          "amplitude": 1, "start": 0, "duration": 0.002}},
      "activation": {"threshold": 0.0005}}},
    "schedule": {"end": )" +
         fmt::format("{}", end) + R"(, "dt": 0.0005},
    "probes": {)" +
         more_probes + R"("diagonal": {"object": "bar", "field": "activation_time",
      "line": {"from": [)" +
         fmt::format("{}", x0) + R"(, 0, 0], "to": [)" + fmt::format("{}", x0 + 0.016) +
         R"(, 0.00025, 0.00025], "points": 33}}},
    "outputs": {"plots": [{"file": "activation.svg", "y": "diagonal.activation_time"}]}
  })";
}

// The Nagumo equation u_t = D u_xx + k u (1 - u)(u - a) has a travelling front of speed
// c = sqrt(D k / 2) (1 - 2a) = 0.35355 mm/ms for D = 1 mm^2/ms, k = 1 /ms, a = 0.25. On a 40 mm
// bar stimulated at one end (x < 2 mm), the activation time (u crossing 1/2) is t0 + x / c once
// the front has formed and before it feels the far end (the no-flux boundary speeds it up over
// the last ~5 mm). Along a line from (10, 0, 0) to (26, h, h) mm it is therefore linear in the
// distance s with slope cos(theta) / c, cos(theta) = 16 / |(16, h, h)|. The grid with
// dx = 0.25 mm and dt = 0.005 ms has a speed error of about 0.2 % (GridMonodomainTest's
// convergence study), so the slope is asserted to 1 % and the profile to be a straight line
// within 0.02 ms over its 45 ms span (linear interpolation between nodes of a field linear in x
// is exact; what is left is the front's discretisation and its last approach to steady speed).
TEST(LineProbe, ActivationTimeOfAPlanarFrontIsLinearInDistance) {
  const std::string scene = NagumoBar(0.085);
  const auto dir = RunScene(scene, "nagumo");
  const CsvTable table = ReadCsv(dir / "probes" / "diagonal.csv");
  ASSERT_EQ(table.num_rows(), 33u);
  const auto& s = table.Column("distance");         // m
  const auto& t = table.Column("activation_time");  // ms
  ASSERT_GT(*std::min_element(t.begin(), t.end()), 0.0) << "the front did not reach the line";
  // Least-squares line t = t0 + slope s (s in mm).
  double ms = 0, mt = 0;
  for (std::size_t j = 0; j < s.size(); ++j) ms += 1e3 * s[j] / 33, mt += t[j] / 33;
  double sst = 0, sss = 0;
  for (std::size_t j = 0; j < s.size(); ++j) {
    sst += (1e3 * s[j] - ms) * (t[j] - mt);
    sss += (1e3 * s[j] - ms) * (1e3 * s[j] - ms);
  }
  const double slope = sst / sss;
  const double h = 0.25, cos_theta = 16 / std::sqrt(16 * 16 + 2 * h * h);
  const double expected = cos_theta / (std::sqrt(0.5) * 0.5);  // ms/mm
  std::printf("activation time along the diagonal: slope %.5f ms/mm (exact %.5f), ", slope,
              expected);
  EXPECT_NEAR(slope, expected, 0.01 * expected);
  double residual = 0;
  for (std::size_t j = 0; j < s.size(); ++j)
    residual = std::max(residual, std::abs(t[j] - (mt + slope * (1e3 * s[j] - ms))));
  std::printf("largest residual %.4f ms\n", residual);
  EXPECT_LT(residual, 0.02);
}

}  // namespace
// Stopped while the front crosses the line, the points it has not reached read the field's
// no-data marker (-1: never activated) instead of a blend of an activation time and -1 (the
// line starts 0.1 mm past a grid plane, so every point interpolates across the front), and the
// points it has passed keep the planar front's profile: consecutive points 0.5 mm / cos(theta)
// apart differ by 0.5 / c = 1.414 ms (to 5 %, the front's speed error plus its last steps).
// Region reductions skip unactivated nodes: the earliest activation of the bar is the stimulus
// region's (under 1 ms), not -1.
TEST(LineProbe, PointsAheadOfTheFrontReadTheNoDataMarker) {
  const std::string region = R"({"box": {"min": [-1, -1, -1], "max": [1, 1, 1]}})";
  const auto dir =
      RunScene(NagumoBar(0.05,
                         R"("first": {"object": "bar", "field": "activation_time", "region": )" +
                             region + R"(, "reduce": "min"},
                        "mean": {"object": "bar", "field": "activation_time", "region": )" +
                             region + R"(, "reduce": "mean"},)",
                         0.0101),
               "nagumo_partial");
  const CsvTable table = ReadCsv(dir / "probes" / "diagonal.csv");
  const auto& t = table.Column("activation_time");
  ASSERT_EQ(t.size(), 33u);
  std::size_t reached = 0;
  while (reached < t.size() && t[reached] != -1) ++reached;
  std::printf("the front reached %zu of 33 points at 50 ms\n", reached);
  ASSERT_GE(reached, 3u);
  ASSERT_LE(reached, 30u);
  for (std::size_t j = reached; j < t.size(); ++j)
    EXPECT_EQ(t[j], -1) << "point " << j << " is ahead of the front";
  const double step = 0.5 / (std::sqrt(0.5) * 0.5);  // ms between points
  for (std::size_t j = 1; j < reached; ++j)
    EXPECT_NEAR(t[j] - t[j - 1], step, 0.05 * step) << "points " << j - 1 << " and " << j;
  const double first = ReadCsv(dir / "probes" / "first.csv").Column("activation_time").back();
  EXPECT_GE(first, 0.0);
  EXPECT_LT(first, 1.0);
  // The mean over activated nodes lies between the first and the latest activation (50 ms).
  const double mean = ReadCsv(dir / "probes" / "mean.csv").Column("activation_time").back();
  EXPECT_GT(mean, first);
  EXPECT_LT(mean, 50.0);
}

}  // namespace gipsi::viz
