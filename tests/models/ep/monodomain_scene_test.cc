// Monodomain from scene files: units, conductivity forms, stimuli, and clear errors for bad
// input. Also the quantity parser the scene loader uses (base/units.h).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/base/units.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/ep/monodomain.h"
#include "io/scene_test_util.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

// A scene with one Monodomain object on a 2 x 1 x 1 mm box; `tissue` replaces its EP keys.
std::string SceneText(const std::string& tissue) {
  return R"({
  "gipsi": 1,
  "meshes": {"box": {"generate": "box", "min": [0, 0, 0], "max": [0.002, 0.001, 0.001],
                     "cells": [4, 2, 2]}},
  "objects": {"tissue": {"type": "Monodomain", "domain": "box", "dt": "0.01 ms", )" +
         tissue + R"(}},
  "schedule": {"end": "0.1 ms"}
})";
}

const std::string kCell = R"("cell": {"model": "AlievPanfilov"}, )";

std::string LoadError(const std::string& text) { return testing::SceneLoadError(text); }

TEST(Units, ConvertsQuantitiesToSi) {
  EXPECT_DOUBLE_EQ(UnitFactor("mS/cm", "S/m"), 0.1);
  EXPECT_DOUBLE_EQ(UnitFactor("uF/cm^2", "F/m^2"), 0.01);
  EXPECT_DOUBLE_EQ(UnitFactor("1/mm", "1/m"), 1000);
  EXPECT_DOUBLE_EQ(UnitFactor("ms", "s"), 1e-3);
  EXPECT_DOUBLE_EQ(UnitFactor("uA/uF", "A/F"), 1);
  EXPECT_DOUBLE_EQ(UnitFactor("mV/ms", "A/F"), 1);  // the cell models' current unit
  EXPECT_THROW((void)UnitFactor("S", "S/m"), std::invalid_argument);
  EXPECT_THROW((void)UnitFactor("mm", "1/m"), std::invalid_argument);  // not reciprocals
  EXPECT_THROW((void)UnitFactor("furlongs per glass", "m"), std::invalid_argument);
}

TEST(MonodomainScene, ReadsQuantitiesWithUnitsAndTheHarmonicMean) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(SceneText(kCell + R"(
      "conductivity": {"intracellular": {"longitudinal": "0.17 S/m", "transverse": 0.019},
                       "extracellular": {"longitudinal": "6.2 mS/cm", "transverse": 0.24}},
      "fibres": {"direction": [0, 2, 0]},
      "surface_to_volume": "140 1/mm", "capacitance": "1 uF/cm^2",
      "stimuli": {"s": {"region": "all", "current": "50000 uA/cm^3", "duration": "2 ms"}})"),
                                    "scene.json", ".", registry);
  const auto& tissue = dynamic_cast<const Monodomain&>(scene.kernel->FindObject("tissue"));
  const EpTissueParams& p = tissue.params();
  EXPECT_NEAR(p.sigma_longitudinal, 0.17 * 0.62 / (0.17 + 0.62), 1e-15);
  EXPECT_NEAR(p.sigma_transverse, 0.019 * 0.24 / (0.019 + 0.24), 1e-15);
  EXPECT_NEAR(p.surface_to_volume, 1.4e5, 1e-9);
  EXPECT_NEAR(p.capacitance, 0.01, 1e-15);
  // 50,000 µA/cm³ / (1400 /cm · 1 µF/cm²) = 35.714 µA/µF.
  ASSERT_EQ(p.stimuli.size(), 1u);
  EXPECT_NEAR(p.stimuli[0].amplitude, 50000.0 / 1400.0, 1e-9);
  EXPECT_NEAR(p.stimuli[0].pulses.duration, 2.0, 1e-12);
  EXPECT_NEAR(tissue.fibres()(1, 0), 1.0, 1e-15);  // normalised
  EXPECT_NEAR(scene.kernel->macro_dt(), 1e-5, 1e-20);
}

// The "parallel" block chooses the diffusion solver of a distributed run: a serial run reads
// and checks it, keeps its own solver, and the keys the block leaves out follow "diffusion".
TEST(MonodomainScene, TheParallelBlockIsCheckedAndKeptForDistributedRuns) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(SceneText(kCell + R"("conductivity": 0.1,
      "diffusion": {"linear_solver": {"preconditioner": "ic", "tolerance": 1e-10}},
      "parallel": {"linear_solver": {"preconditioner": "hypre"}})"),
                                    "scene.json", ".", registry);
  const auto& tissue = dynamic_cast<const Monodomain&>(scene.kernel->FindObject("tissue"));
  const EpTissueParams& p = tissue.params();
  EXPECT_EQ(p.linear.preconditioner, "ic");
  ASSERT_TRUE(p.distributed_linear.has_value());
  EXPECT_EQ(p.distributed_linear->type, "cg");
  EXPECT_EQ(p.distributed_linear->preconditioner, "hypre");
  EXPECT_EQ(p.distributed_linear->tolerance, 1e-10);
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": 0.1,
      "parallel": {"linear_solver": {"preconditioner": "ic"}})")),
              HasSubstr("objects.tissue.parallel.linear_solver.preconditioner"));
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": 0.1,
      "parallel": {"linear_solver": {"type": "umfpack"}})")),
              HasSubstr("objects.tissue.parallel.linear_solver.type"));
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": 0.1,
      "parallel": {"linear_solver": {"max_iterations": 0}})")),
              HasSubstr("objects.tissue.parallel.linear_solver.max_iterations: expected a number "
                        "of iterations in [1, 1000000]"));
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": 0.1, "parallel": {"ranks": 4})")),
              HasSubstr("objects.tissue.parallel"));
}

TEST(MonodomainScene, BadInputGetsAClearError) {
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": -0.1)")),
              HasSubstr("objects.tissue.conductivity: expected a positive quantity"));
  EXPECT_THAT(
      LoadError(SceneText(kCell + R"("conductivity": {"longitudinal": 0.2, "transverse": -1})")),
      HasSubstr("objects.tissue.conductivity.transverse: expected a non-negative quantity"));
  EXPECT_THAT(
      LoadError(SceneText(kCell + R"("conductivity": {"longitudinal": 0.2, "transverse": 0.1})")),
      HasSubstr("needs a fibre direction"));
  EXPECT_THAT(LoadError(SceneText(R"("cell": {"model": "Hodgkin"}, "conductivity": 0.1)")),
              HasSubstr("objects.tissue.cell.model"));
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": 0.1, "surface_to_volume": "140 mm")")),
              HasSubstr("objects.tissue.surface_to_volume: \"140 mm\": 'mm' cannot be converted "
                        "to 1/m"));
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": "0.1 S")")),
              HasSubstr("cannot be converted to S/m"));
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": 0.1, "stimuli": {"s": {
      "region": {"sphere": {"center": [1, 1, 1], "radius": 0.001}}, "amplitude": 50,
      "duration": 0.001}})")),
              HasSubstr("stimulus 's' selects no node"));
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": 0.1, "stimuli": {"s": {
      "region": "all", "amplitude": 50, "current": 1, "duration": 0.001}})")),
              HasSubstr("objects.tissue.stimuli.s: give exactly one of"));
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": 0.1, "reaction": {"dt": "1 mV"})")),
              HasSubstr("objects.tissue.reaction.dt"));
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": 0.1, "activation": {
      "apd_repolarisation": 90})")),
              HasSubstr("a fraction in (0, 1)"));
  // Mechanical conditions, which a Monodomain would have ignored, silently.
  EXPECT_THAT(LoadError(SceneText(kCell + R"("conductivity": 0.1, "boundary_conditions": [
      {"name": "base", "region": {"group": "xmin"}, "fix": true}])")),
              HasSubstr("objects.tissue.boundary_conditions: an EP tissue takes no boundary "
                        "conditions"));
}

}  // namespace
}  // namespace gipsi
