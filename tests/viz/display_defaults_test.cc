// What the viewer and snapshots show when the scene and command line say nothing (issue 22):
// electrophysiology coloured by V, no inputs that nothing drives offered as colour fields, a
// field's no-data marker not drawn as a value, and electrophysiology drawn on the moving muscle
// of the same tissue.

#include <gtest/gtest.h>

#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/display_manager.h"
#include "test_paths.h"

namespace gipsi::viz {
namespace {

constexpr const char* kBar = R"({
    "objects": {"bar": {"type": "GridMonodomain", "dt": 1e-5,
      "grid": {"min": [0, 0, 0], "max": [0.002, 0.001, 0.001], "cells": [2, 1, 1]},
      "cell": {"model": "MitchellSchaeffer"}, "fibres": {"direction": [1, 0, 0]},
      "conductivity": {"longitudinal": 0.1, "transverse": 0.01},
      "display": {"as": "points"DISPLAY}}},
    "schedule": {"end": 1e-5}
  })";

Scene LoadBar(TypeRegistry& registry, const std::string& display = "") {
  RegisterBuiltins(registry);
  std::string text = kBar;
  text.replace(text.find("DISPLAY"), 7, display);
  return LoadSceneFromString(text, "bar.json", ".", registry);
}

TEST(DisplayDefaults, AnElectrophysiologyObjectIsColouredByItsPotential) {
  // Before, an EP scene opened in solid colours.
  TypeRegistry registry;
  Scene scene = LoadBar(registry);
  SceneDisplay display(*scene.kernel, scene.display, {});
  ASSERT_EQ(display.size(), 1u);
  EXPECT_EQ(display.manager(0).spec().field, "V");
  EXPECT_EQ(display.manager(0).spec().color_map, "cool-warm");
  // The command line's or the scene's choice still wins.
  ColorSpec solid;
  SceneDisplay chosen(*scene.kernel, scene.display, {{"bar", solid}});
  EXPECT_EQ(chosen.manager(0).spec().field, "");
}

TEST(DisplayDefaults, AScalarIsDrawnWithItsSign) {
  // The resting potential is negative; before, a scalar's default "magnitude" drew |V| (the
  // heart's legend read 79.98 to 80 mV at rest).
  TypeRegistry registry;
  Scene scene = LoadBar(registry);
  SceneDisplay display(*scene.kernel, scene.display, {});
  FrameBuffers frame;
  display.Fill(0, frame);
  const SimObject& bar = scene.kernel->FindObject("bar");
  Eigen::MatrixXd v(1, bar.domain().num_nodes());
  bar.ReadField(bar.FindField("V"), v);
  ASSERT_LT(v.maxCoeff(), 0);
  ASSERT_EQ(frame.surfaces[0].values.size(), std::size_t(v.cols()));
  for (Index n = 0; n < v.cols(); ++n)
    EXPECT_EQ(frame.surfaces[0].values[std::size_t(n)], float(v(n)));
  EXPECT_LT(frame.surfaces[0].range_hi, 0);
}

TEST(DisplayDefaults, ANoDataMarkerIsNotDrawnAsAValue) {
  // activation_time is -1 at nodes the front has not reached: grey, out of the range, NaN in
  // the values (before, -1 was coloured as a time and stretched the range).
  TypeRegistry registry;
  Scene scene = LoadBar(registry, R"(, "color": {"field": "activation_time"})");
  SceneDisplay display(*scene.kernel, scene.display, {});
  FrameBuffers frame;
  display.Fill(0, frame);
  const SurfaceBuffers& out = frame.surfaces[0];
  ASSERT_EQ(out.num_vertices(), 12u);
  EXPECT_EQ(out.num_no_data, 12u);
  EXPECT_EQ(out.range_lo, 0);
  EXPECT_EQ(out.range_hi, 0);
  for (std::size_t v = 0; v < 12; ++v) {
    EXPECT_TRUE(std::isnan(out.values[v]));
    for (int c = 0; c < 3; ++c) EXPECT_EQ(out.colors[3 * v + std::size_t(c)], kNoDataColor[c]);
  }
}

TEST(DisplayDefaults, AScalarHasNoComponentBoxAndAVectorNamesItsAxes) {
  // The viewer offered "magnitude, x, y, z" for the potential V too, which has no axes
  // (choosing y or z failed: "component 1 does not exist").
  TypeRegistry registry;
  Scene scene = LoadBar(registry);
  const SimObject& bar = scene.kernel->FindObject("bar");
  EXPECT_TRUE(ComponentChoices(bar.field_info(bar.FindField("V")).components).empty());
  Scene liver = LoadScene(std::string(GIPSI_SOURCE_DIR) + "/scenes/hanging_liver.json", registry);
  const SimObject& mass_spring = liver.kernel->FindObject("liver");
  EXPECT_EQ(
      ComponentChoices(mass_spring.field_info(mass_spring.FindField("displacement")).components),
      (std::vector<std::string>{"magnitude", "x", "y", "z"}));
  // A tensor's components by index, as the colour bar labels them.
  const std::vector<std::string> tensor = ComponentChoices(9);
  ASSERT_EQ(tensor.size(), 10u);
  EXPECT_EQ(tensor[1], "[0]");
  EXPECT_EQ(tensor[9], "[8]");
}

TEST(DisplayDefaults, InputsNothingDrivesAreNotOfferedToColourBy) {
  // A mass-spring liver declares the heart's coupling inputs (fibre, nodal_active_tension);
  // nothing drives them there, so the viewer does not offer them. Before, it offered every
  // readable field.
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadScene(std::string(GIPSI_SOURCE_DIR) + "/scenes/hanging_liver.json", registry);
  const SimObject& liver = scene.kernel->FindObject("liver");
  auto offers = [&](const char* name) { return OffersField(liver, liver.FindField(name)); };
  EXPECT_FALSE(offers("fibre"));
  EXPECT_FALSE(offers("nodal_active_tension"));
  EXPECT_FALSE(offers("external_force"));
  EXPECT_FALSE(offers("kinetic_energy"));  // global: not a colour
  EXPECT_TRUE(offers("displacement"));
  EXPECT_TRUE(offers("velocity"));
  EXPECT_TRUE(offers("position"));
  EXPECT_TRUE(offers("mass"));
}

TEST(DisplayDefaults, ElectrophysiologyIsDrawnOnTheMovingMuscleOfTheSameTissue) {
  // heart.json: bioelectricity and muscle on the same mesh. Before, the bioelectricity surface
  // stayed at rest and poked through the contracted muscle.
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadScene(std::string(GIPSI_SOURCE_DIR) + "/scenes/heart.json", registry);
  ASSERT_TRUE(scene.kernel->Run(0.3).ok());  // into the first contraction
  SceneDisplay display(*scene.kernel, scene.display, {});
  ASSERT_EQ(display.size(), 2u);
  EXPECT_EQ(display.manager(0).name(), "heart.bioelectricity");
  EXPECT_EQ(display.manager(1).name(), "heart.muscle");
  const SimObject& muscle = scene.kernel->FindObject("heart.muscle");
  EXPECT_EQ(&display.manager(0).geometry_object(), &muscle);
  EXPECT_EQ(display.Hidden(), (std::vector<bool>{false, true}));  // one surface, not two
  FrameBuffers frame;
  display.Fill(0.3, frame);
  const SurfaceBuffers& ep = frame.surfaces[0];
  const SurfaceBuffers& wall = frame.surfaces[1];
  ASSERT_EQ(ep.positions.size(), wall.positions.size());
  double moved = 0;
  for (std::size_t i = 0; i < ep.positions.size(); ++i) {
    EXPECT_EQ(ep.positions[i], wall.positions[i]) << i;
    const std::size_t v = i / 3;
    const int node = muscle.boundary().vertex_to_node[v];
    moved = std::max(moved,
                     std::abs(double(ep.positions[i]) - muscle.domain().nodes(int(i % 3), node)));
  }
  EXPECT_GT(moved, 1e-4);  // the muscle has moved from rest by more than 0.1 mm
  // Colouring the muscle on the command line shows it and hides the electrophysiology instead.
  ColorSpec by_displacement;
  by_displacement.field = "displacement";
  SceneDisplay muscle_chosen(*scene.kernel, scene.display, {{"muscle", by_displacement}});
  EXPECT_EQ(muscle_chosen.Hidden(), (std::vector<bool>{true, false}));
  EXPECT_EQ(&muscle_chosen.manager(0).geometry_object(), &muscle);
}

}  // namespace
}  // namespace gipsi::viz
