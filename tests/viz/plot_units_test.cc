// Plot axes in units other than the fields' SI units (`x_unit`, `y_unit`), converted by
// UDUNITS-2, and the SI units shown in the labels by default.

#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/plot_data.h"
#include "io/scene_test_util.h"

namespace gipsi::viz {
namespace {

using ::testing::HasSubstr;

/// A resting FEM block with a probe "e" of two global fields in joules, and `plots`.
std::string EnergyScene(const std::string& plots) {
  return R"({
    "meshes": {"block": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [1, 1, 1]}},
    "objects": {"block": {"type": "FemSolid", "domain": "block", "dt": 0.01, "density": 1000,
      "material": {"law": "Corotational", "youngs_modulus": 1e5, "poisson_ratio": 0.3},
      "integrator": "BackwardEuler"}},
    "schedule": {"end": 0.02},
    "probes": {"e": {"object": "block", "fields": ["kinetic_energy", "strain_energy"]}},
    "outputs": {"plots": )" +
         plots + R"(}
  })";
}

PlotSpec ParseOne(const std::string& plots) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(EnergyScene(plots), "units.json", ".", registry);
  EXPECT_EQ(scene.plots.size(), 1u);
  return scene.plots.at(0);
}

TEST(PlotUnits, ConvertsTheColumnsAndNamesTheUnitsInTheLabels) {
  const PlotSpec spec = ParseOne(R"([{"file": "e.png", "x": "e.kinetic_energy",
      "y": "e.strain_energy", "x_unit": "mJ", "y_unit": "uJ"}])");
  // Exact decimal factors: UDUNITS-2 scales by powers of ten.
  EXPECT_DOUBLE_EQ(spec.x_scale, 1e3);
  EXPECT_DOUBLE_EQ(spec.y_scale, 1e6);
  const auto dir =
      std::filesystem::temp_directory_path() / ("gipsi_plot_units_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "e.csv") << "time,kinetic_energy,strain_energy\n0.01,0.002,3e-6\n"
                                  "0.02,0.004,5e-6\n";
  const PlotData data = LoadPlotData(spec, dir);
  std::filesystem::remove_all(dir);
  ASSERT_EQ(data.series.size(), 1u);
  EXPECT_DOUBLE_EQ(data.series[0].x[0], 2.0);
  EXPECT_DOUBLE_EQ(data.series[0].x[1], 4.0);
  EXPECT_DOUBLE_EQ(data.series[0].y[0], 3.0);
  EXPECT_DOUBLE_EQ(data.series[0].y[1], 5.0);
  EXPECT_EQ(data.x_label, "kinetic energy [mJ]");
  EXPECT_EQ(data.y_label, "strain energy [uJ]");
}

TEST(PlotUnits, WithoutUnitsTheLabelsShowTheSiUnits) {
  const PlotSpec spec = ParseOne(R"([{"file": "e.png", "y": "e.strain_energy"}])");
  EXPECT_EQ(spec.x_unit, "s");
  EXPECT_EQ(spec.y_unit, "J");
  EXPECT_EQ(spec.x_scale, 1.0);
  EXPECT_EQ(spec.y_scale, 1.0);
}

TEST(PlotUnits, AUnitOfAnotherDimensionOrUnknownIsAnErrorNamingItsPath) {
  const std::string mmhg = testing::SceneLoadError(
      EnergyScene(R"([{"file": "e.png", "y": "e.strain_energy", "y_unit": "mmHg"}])"));
  EXPECT_THAT(mmhg, HasSubstr("scene.json: outputs.plots[0].y_unit"));
  EXPECT_THAT(mmhg, HasSubstr("a unit that converts from the column's unit 'J'"));
  EXPECT_THAT(testing::SceneLoadError(EnergyScene(
                  R"([{"file": "e.png", "y": "e.strain_energy", "x_unit": "furlongz"}])")),
              HasSubstr("outputs.plots[0].x_unit"));
}

}  // namespace
}  // namespace gipsi::viz
