#include "gipsi/viz/render/plot.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "apps/cli_test_util.h"
#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/render/image.h"

namespace gipsi::viz {
namespace {

using ::testing::HasSubstr;

/// Pixel centres drawn in the first series' colour (cairo anti-aliases the line's edges, so
/// only pixels close to the colour count).
std::vector<Eigen::Vector2d> TracePixels(const Image& image) {
  const double r = (kPlotColors[0] >> 16) & 0xff, g = (kPlotColors[0] >> 8) & 0xff,
               b = kPlotColors[0] & 0xff;
  std::vector<Eigen::Vector2d> pixels;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const Rgb c = image.At(x, y);
      if (std::abs(c.r * 255 - r) < 30 && std::abs(c.g * 255 - g) < 30 &&
          std::abs(c.b * 255 - b) < 30)
        pixels.emplace_back(x + 0.5, y + 0.5);
    }
  return pixels;
}

PlotData Series(std::vector<double> x, std::vector<double> y) {
  PlotData data;
  data.x_label = "x";
  data.y_label = "y";
  data.series.push_back({"y", std::move(x), std::move(y)});
  return data;
}

TEST(WritePlot, DrawsAStraightLineForLinearData) {
  std::vector<double> x, y;
  for (int i = 0; i <= 10; ++i) {
    x.push_back(0.1 * i);
    y.push_back(2 * x.back() + 1);
  }
  const auto dir = gipsi::testing::TempDir("gipsi_plot_", "line");
  WritePlot(Series(x, y), dir / "line.png");
  const Image image = ReadPng(dir / "line.png");
  EXPECT_EQ(image.width, 800);
  EXPECT_EQ(image.height, 500);
  EXPECT_EQ(image.At(2, 2), (Rgb{1, 1, 1}));  // white background
  const auto pixels = TracePixels(image);
  ASSERT_GT(pixels.size(), 300u);  // a line across most of the ~650 px wide plot box
  // Least-squares line through the trace pixels: every pixel within 1.5 px of it (the line is
  // 2 px wide), and rising to the right (pixel y grows downwards).
  Eigen::MatrixXd A(pixels.size(), 2);
  Eigen::VectorXd rhs(pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    A(Index(i), 0) = pixels[i].x();
    A(Index(i), 1) = 1;
    rhs(Index(i)) = pixels[i].y();
  }
  const Eigen::Vector2d fit = A.colPivHouseholderQr().solve(rhs);
  EXPECT_LT(fit(0), 0);
  EXPECT_LT((A * fit - rhs).cwiseAbs().maxCoeff() / std::sqrt(1 + fit(0) * fit(0)), 1.5);
}

TEST(WritePlot, DrawsAClosedLoopOfOneColumnAgainstAnother) {
  std::vector<double> x, y;  // a pressure-volume-like loop: a circle in data coordinates
  for (int i = 0; i <= 400; ++i) {
    x.push_back(std::cos(2 * M_PI * i / 400));
    y.push_back(std::sin(2 * M_PI * i / 400));
  }
  const auto dir = gipsi::testing::TempDir("gipsi_plot_", "loop");
  WritePlot(Series(x, y), dir / "loop.png");
  const auto pixels = TracePixels(ReadPng(dir / "loop.png"));
  ASSERT_GT(pixels.size(), 500u);
  // The axes scale x and y separately, so the circle becomes an ellipse filling the trace's
  // bounding box: every trace pixel lies on it to within the line width (2 px over a radius of
  // ~180 px: 0.05 in normalised units).
  Eigen::Vector2d lo = pixels[0], hi = pixels[0];
  for (const auto& p : pixels) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Eigen::Vector2d centre = 0.5 * (lo + hi), radius = 0.5 * (hi - lo);
  EXPECT_GT(radius.minCoeff(), 100);
  for (const auto& p : pixels)
    EXPECT_NEAR((p - centre).cwiseQuotient(radius).norm(), 1.0, 0.05) << p.transpose();
}

TEST(WritePlot, WritesSvgWithALegendForSeveralSeries) {
  PlotData data = Series({0, 1, 2}, {0, 1, 4});
  data.series.push_back({"second", {0, 1, 2}, {1, 1, std::nan("")}});  // a gap at the NaN
  const auto dir = gipsi::testing::TempDir("gipsi_plot_", "svg");
  WritePlot(data, dir / "p.svg");
  std::ifstream in(dir / "p.svg");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_THAT(text.str(), HasSubstr("<svg"));
  EXPECT_THAT(text.str(), HasSubstr("stroke:rgb(12.156863%,46.666667%,70.588235%)"));  // #1f77b4
  EXPECT_THAT(text.str(), HasSubstr("stroke:rgb(100%,49.803922%,5.490196%)"));         // #ff7f0e
}

TEST(WritePlot, PutsTheLegendRightOfTheAxesAndNeverOnTheData) {
  // Two series with long labels (as the heart's pressure plot has): the legend must sit in a
  // strip right of the axes' frame, inside the image, and no legend text may fall inside the
  // frame, where it would cover the curves (it once sat on them).
  PlotData data = Series({0, 1, 2}, {0, 1, 4});
  data.series[0].label = "left ventricular pressure [mmHg]";
  data.series.push_back({"aortic pressure at the valve [mmHg]", {0, 1, 2}, {4, 1, 0}});
  const auto dir = gipsi::testing::TempDir("gipsi_plot_", "legend");
  WritePlot(data, dir / "p.png");
  const Image image = ReadPng(dir / "p.png");
  // Black lines and text, anti-aliased over two pixels (a 1-px frame line reads as two 50 %
  // grey columns): a dark neutral grey. The series' colours and their blends are not neutral.
  const auto dark = [&](int x, int y) {
    const Rgb c = image.At(x, y);
    const float hi = std::max({c.r, c.g, c.b}), lo = std::min({c.r, c.g, c.b});
    return hi < 0.6f && hi - lo < 0.1f;
  };
  // The frame's vertical sides are the columns of dark pixels taller than half the image (the
  // legend's own box is a few text lines tall).
  std::vector<int> frame_columns;
  for (int x = 0; x < image.width; ++x) {
    int count = 0;
    for (int y = 0; y < image.height; ++y) count += dark(x, y) ? 1 : 0;
    if (count > image.height / 2) frame_columns.push_back(x);
  }
  ASSERT_GE(frame_columns.size(), 2u);
  const int left = frame_columns.front(), right = frame_columns.back();
  ASSERT_GT(right - left, image.width / 3);  // the data keep most of the width
  int top = image.height, bottom = 0;        // the frame's rows, from its right side
  for (int y = 0; y < image.height; ++y)
    if (dark(right, y)) top = std::min(top, y), bottom = std::max(bottom, y);
  // Legend samples: the second series' colour right of the frame, within the image and the
  // frame's height (the strip is centred on the axes).
  const double r = (kPlotColors[1] >> 16) & 0xff, g = (kPlotColors[1] >> 8) & 0xff,
               b = kPlotColors[1] & 0xff;
  int samples = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = right + 1; x < image.width; ++x) {
      const Rgb c = image.At(x, y);
      if (std::abs(c.r * 255 - r) < 30 && std::abs(c.g * 255 - g) < 30 &&
          std::abs(c.b * 255 - b) < 30) {
        ++samples;
        EXPECT_GT(y, top);
        EXPECT_LT(y, bottom);
      }
    }
  EXPECT_GT(samples, 20);  // a 2 px line about 0.08 of the viewport wide
  // Inside the frame (away from its ticks, 12 px) only curves and the light grid are drawn:
  // no dark legend text or box.
  int dark_inside = 0;
  for (int y = top + 12; y < bottom - 12; ++y)
    for (int x = left + 12; x < right - 12; ++x) dark_inside += dark(x, y) ? 1 : 0;
  EXPECT_EQ(dark_inside, 0);
  // The legend's text is dark and right of the frame, and it is not cut at the image's edge:
  // the last column holds no text.
  int dark_right = 0, dark_edge = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = right + 4; x < image.width; ++x) dark_right += dark(x, y) ? 1 : 0;
    dark_edge += dark(image.width - 1, y) ? 1 : 0;
  }
  EXPECT_GT(dark_right, 200);
  EXPECT_EQ(dark_edge, 0);
}

TEST(WritePlot, RejectsUnknownFormatsAndEmptyData) {
  const auto dir = gipsi::testing::TempDir("gipsi_plot_", "bad");
  try {
    WritePlot(Series({0, 1}, {0, 1}), dir / "p.jpg");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("p.jpg: expected a plot file name ending in .png or .svg"));
  }
  try {
    WritePlot(Series({0, 1}, {std::nan(""), std::nan("")}), dir / "p.png");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("nothing to plot: the columns hold no finite points"));
  }
}

/// A scene whose run ends with a plot of a probe.
std::string PlotScene(const std::string& plots) {
  return R"({
    "meshes": {"cube": {"generate": "box", "min": [0, 0, 0], "max": [0.05, 0.05, 0.05],
                        "cells": [2, 2, 2]}},
    "objects": {"cube": {"type": "MassSpring", "domain": "cube", "density": 1000,
      "stiffness": 200, "damping": 0.1, "integrator": "SymplecticEuler", "dt": 0.0001}},
    "schedule": {"end": 0.05, "dt": 0.001},
    "probes": {"corner": {"object": "cube", "point": [0, 0, 0], "fields": ["displacement"]},
               "energy": {"object": "cube", "fields": ["kinetic_energy"]}},
    "outputs": {"vtu": false, "plots": )" +
         plots + "}}";
}

std::string LoadError(const std::string& plots) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  try {
    (void)LoadSceneFromString(PlotScene(plots), "s.json", ".", registry);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ScenePlots, AreCheckedAgainstTheProbesWhenTheSceneLoads) {
  EXPECT_EQ(LoadError(R"([{"file": "a.png", "y": ["corner.displacement_z"]},
                          {"file": "b.svg", "x": "corner.displacement_x",
                           "y": "corner.displacement_z"}])"),
            "no error");
  EXPECT_THAT(LoadError(R"([{"file": "a.png", "y": ["coner.displacement_z"]}])"),
              HasSubstr("s.json: outputs.plots[0].y[0]: no probe named 'coner' (did you mean "
                        "'corner'?) in 'probes'"));
  EXPECT_THAT(LoadError(R"([{"file": "a.png", "y": "corner.displacement"}])"),
              HasSubstr("outputs.plots[0].y: probe 'corner' has no column 'displacement'"));
  EXPECT_THAT(LoadError(R"([{"file": "a.png", "x": "corner.displacement_x",
                             "y": ["energy.kinetic_energy"]}])"),
              HasSubstr("outputs.plots[0].y[0]: comes from probe 'energy', but x comes from "
                        "probe 'corner'"));
  EXPECT_THAT(LoadError(R"([{"file": "a.jpg", "y": "corner.time"}])"),
              HasSubstr("outputs.plots[0].file: expected a file name ending in .png or .svg"));
  EXPECT_THAT(LoadError(R"([{"file": "a.png", "y": "corner"}])"),
              HasSubstr("outputs.plots[0].y: expected PROBE.COLUMN"));
}

TEST(ScenePlots, AreWrittenWhenARunEnds) {
  const auto dir = gipsi::testing::TempDir("gipsi_plot_", "run");
  std::ofstream(dir / "s.json") << PlotScene(
      R"([{"file": "corner.png", "y": ["corner.displacement_z"], "title": "corner"}])");
  const auto result = gipsi::testing::Gipsi(
      fmt::format("run {} -q -o {}", (dir / "s.json").string(), (dir / "out").string()));
  ASSERT_EQ(result.code, 0) << result.output;
  const Image image = ReadPng(dir / "out" / "corner.png");
  EXPECT_EQ(image.width, 800);
  EXPECT_GT(TracePixels(image).size(), 100u);
}

TEST(PlotCommand, PlotsCsvColumnsAndNamesUnknownOnes) {
  const auto dir = gipsi::testing::TempDir("gipsi_plot_", "cli");
  {
    std::ofstream csv(dir / "t.csv");
    csv << "time,a,b\n";
    for (int i = 0; i <= 20; ++i) csv << 0.1 * i << "," << i * i << "," << -i << "\n";
  }
  auto r = gipsi::testing::Gipsi(fmt::format("plot {} --y a --y b --size 400x300 --out {}",
                                             (dir / "t.csv").string(), (dir / "t.png").string()));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("400 x 300, 2 series of 21 rows"));
  EXPECT_EQ(ReadPng(dir / "t.png").height, 300);
  r = gipsi::testing::Gipsi(
      fmt::format("plot {} --y c --out {}", (dir / "t.csv").string(), (dir / "t.png").string()));
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.output, HasSubstr("t.csv: no column 'c'"));
}

}  // namespace
}  // namespace gipsi::viz
