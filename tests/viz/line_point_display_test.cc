// Display managers for line sets (springs, mesh edges) and point sets (domain nodes), and the
// scene's "display" keys that choose how objects are drawn.

#include <set>
#include <utility>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/mass_spring/mass_spring.h"
#include "gipsi/numerics/ode.h"
#include "gipsi/viz/display_manager.h"
#include "io/scene_test_util.h"

namespace gipsi::viz {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

/// A spring network without elements: an L of three nodes, springs (0, 1) and (1, 2).
std::unique_ptr<MassSpring> MakeChain() {
  Points nodes(3, 3);
  nodes << 0, 1, 1,  //
      0, 0, 2,       //
      0, 0, 0;
  Eigen::Matrix2Xi springs(2, 2);
  springs << 0, 1,  //
      1, 2;
  return std::make_unique<MassSpring>("chain", nodes, springs, VecX::Ones(3), MassSpringParams{},
                                      std::make_unique<SymplecticEuler>());
}

/// A unit-cube MassSpring block (one cell of 6 tets) with the given "display" entry.
std::string BlockScene(const std::string& display) {
  return R"({
    "meshes": {"block": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [1, 1, 1]}},
    "objects": {"block": {"type": "MassSpring", "domain": "block", "dt": 1e-4)" +
         (display.empty() ? std::string() : ", \"display\": " + display) + R"(}},
    "schedule": {"end": 1e-4}
  })";
}

Scene LoadText(const std::string& text, TypeRegistry& registry) {
  RegisterBuiltins(registry);
  return LoadSceneFromString(text, "scene.json", ".", registry);
}

/// An object type the viewer knows nothing about (as a plugin's would be): three nodes joined
/// by its own segments (0, 2) and (2, 1), e.g. a rod model drawn as its centre line.
class Rod final : public SimObject {
 public:
  Rod() : SimObject("rod") {
    Mesh mesh;
    mesh.nodes = Points(3, 3);
    mesh.nodes << 0, 2, 1,  //
        0, 0, 0,            //
        0, 0, 1;
    positions_ = mesh.nodes;
    SetGeometry(std::make_shared<const Mesh>(std::move(mesh)), BoundarySurface{});
  }
  std::string_view type_name() const override { return "Rod"; }
  const Points& domain_positions() const override { return positions_; }
  Eigen::Matrix2Xi DisplaySegments() const override {
    Eigen::Matrix2Xi s(2, 2);
    s << 0, 2,  //
        2, 1;
    return s;
  }

 protected:
  StepStatus DoStep(double, double) override { return StepStatus::Ok(); }
  void DoReadField(FieldId, Eigen::Ref<Eigen::MatrixXd>) const override {}
  void DoWriteField(FieldId, const Eigen::Ref<const Eigen::MatrixXd>&) override {}

 private:
  Points positions_;
};

TEST(LineDisplay, AnyObjectWithItsOwnSegmentsIsDrawnAsThemByDefault) {
  Rod rod;
  EXPECT_TRUE(DisplayManager::HasDefaultGeometry(rod));
  DisplayManager manager(rod, ColorSpec{});
  EXPECT_EQ(manager.primitive(), Primitive::kLines);
  SurfaceBuffers out;
  manager.Fill(out);
  EXPECT_THAT(out.positions, ElementsAre(0, 0, 0, 2, 0, 0, 1, 0, 1));
  EXPECT_THAT(out.indices, ElementsAre(0, 2, 2, 1));
}

TEST(LineDisplay, ASpringNetworkIsDrawnAsItsSpringsByDefault) {
  auto chain = MakeChain();
  ASSERT_EQ(chain->display().triangles.cols(), 0);  // nothing else to draw
  EXPECT_TRUE(DisplayManager::HasDefaultGeometry(*chain));
  DisplayManager manager(*chain, ColorSpec{});
  EXPECT_EQ(manager.primitive(), Primitive::kLines);
  SurfaceBuffers out;
  manager.Fill(out);
  EXPECT_EQ(out.primitive, Primitive::kLines);
  EXPECT_THAT(out.positions, ElementsAre(0, 0, 0, 1, 0, 0, 1, 2, 0));
  EXPECT_THAT(out.indices, ElementsAre(0, 1, 1, 2));                 // the springs, in their order
  EXPECT_THAT(out.normals, ElementsAre(0, 0, 0, 0, 0, 0, 0, 0, 0));  // drawn unshaded
  EXPECT_EQ(out.num_triangles(), 0u);
  EXPECT_EQ(out.size, 2.0f);  // the default line width
  const Rgb solid = ColorSpec{}.solid;
  for (std::size_t v = 0; v < 3; ++v) {
    EXPECT_EQ(out.colors[3 * v], solid.r);
    EXPECT_EQ(out.colors[3 * v + 2], solid.b);
  }
}

TEST(LineDisplay, ColoursTheSpringNodesByAFieldWithAutomaticOrFixedRange) {
  auto chain = MakeChain();
  ColorSpec spec;
  spec.field = "position";
  spec.component = 1;  // y = 0, 0, 2 at the three nodes
  spec.color_map = "grey";
  DisplayManager automatic(*chain, spec);
  SurfaceBuffers out;
  automatic.Fill(out);
  EXPECT_EQ(out.range_lo, 0.0);
  EXPECT_EQ(out.range_hi, 2.0);
  EXPECT_THAT(out.values, ElementsAre(0, 0, 2));
  // Grey: colour = (y - lo) / (hi - lo) in every channel, exactly representable here.
  EXPECT_THAT(out.colors, ElementsAre(0, 0, 0, 0, 0, 0, 1, 1, 1));
  spec.range = std::pair{0.0, 4.0};
  DrawSpec draw;
  draw.color = spec;
  draw.size = 5;
  DisplayManager fixed(*chain, draw);
  fixed.Fill(out);
  EXPECT_EQ(out.range_hi, 4.0);
  EXPECT_THAT(out.colors, ElementsAre(0, 0, 0, 0, 0, 0, 0.5, 0.5, 0.5));
  EXPECT_EQ(out.size, 5.0f);
  // Moving a node moves its line end: positions follow the state.
  Eigen::MatrixXd x = chain->domain_positions();
  x(2, 2) = 3;
  chain->WriteField(chain->FindField("position"), x);
  fixed.Fill(out);
  EXPECT_EQ(out.positions[8], 3.0f);
}

TEST(LineDisplay, ATetMeshIsDrawnAsItsUniqueEdges) {
  TypeRegistry registry;
  Scene scene = LoadText(BlockScene(R"({"as": "lines"})"), registry);
  const SimObject& block = scene.kernel->FindObject("block");
  const Mesh& mesh = block.domain();
  ASSERT_EQ(mesh.num_tets(), 6);
  DisplayManager manager(block, DrawSpec{{}, Primitive::kLines});
  SurfaceBuffers out;
  manager.Fill(out);
  ASSERT_EQ(out.primitive, Primitive::kLines);
  // The cube split into 6 tets around a body diagonal has its 12 edges, one diagonal on each of
  // its 6 faces and the body diagonal: 19 segments, each the sorted pair of a tet edge, none
  // repeated.
  ASSERT_EQ(out.indices.size(), 38u);
  std::set<std::pair<std::uint32_t, std::uint32_t>> expected, drawn;
  for (Index e = 0; e < mesh.num_tets(); ++e)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        if (mesh.tets(i, e) < mesh.tets(j, e))
          expected.emplace(std::uint32_t(mesh.tets(i, e)), std::uint32_t(mesh.tets(j, e)));
  for (std::size_t k = 0; k < out.indices.size(); k += 2)
    drawn.emplace(out.indices[k], out.indices[k + 1]);
  EXPECT_EQ(drawn, expected);
  EXPECT_EQ(drawn.size(), 19u);
  int edges = 0, diagonals = 0, body = 0;
  for (auto [a, b] : drawn) {
    const double length = (mesh.nodes.col(a) - mesh.nodes.col(b)).norm();
    edges += std::abs(length - 1) < 1e-12;
    diagonals += std::abs(length - std::sqrt(2.0)) < 1e-12;
    body += std::abs(length - std::sqrt(3.0)) < 1e-12;
  }
  EXPECT_EQ(edges, 12);
  EXPECT_EQ(diagonals, 6);
  EXPECT_EQ(body, 1);
  ASSERT_EQ(out.num_vertices(), std::size_t(mesh.num_nodes()));
  for (Index n = 0; n < mesh.num_nodes(); ++n)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(out.positions[std::size_t(3 * n + k)], mesh.nodes(k, n));
}

TEST(PointDisplay, NodesAreDrawnAsPointsColouredByANodeField) {
  TypeRegistry registry;
  Scene scene = LoadText(BlockScene(""), registry);
  const SimObject& block = scene.kernel->FindObject("block");
  DrawSpec draw;
  draw.as = Primitive::kPoints;
  draw.color.field = "position";
  draw.color.component = 2;
  draw.color.color_map = "grey";
  DisplayManager manager(block, draw);
  SurfaceBuffers out;
  manager.Fill(out);
  const Mesh& mesh = block.domain();
  ASSERT_EQ(out.primitive, Primitive::kPoints);
  ASSERT_EQ(out.num_vertices(), std::size_t(mesh.num_nodes()));
  ASSERT_EQ(out.indices.size(), std::size_t(mesh.num_nodes()));
  EXPECT_EQ(out.size, 6.0f);  // the default point size
  for (std::size_t n = 0; n < out.num_vertices(); ++n) {
    EXPECT_EQ(out.indices[n], n);
    const double z = mesh.nodes(2, Index(n));  // 0 or 1 on the unit cube: grey 0 or 1
    EXPECT_EQ(out.values[n], z);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(out.colors[3 * n + std::size_t(k)], z);
  }
}

TEST(PointDisplay, AGridDomainsNodesArePoints) {
  TypeRegistry registry;
  Scene scene = LoadText(R"({
    "objects": {"tissue": {"type": "GridMonodomain", "dt": 1e-5,
      "grid": {"min": [0, 0, 0], "max": [0.002, 0.001, 0.001], "cells": [2, 1, 1]},
      "cell": {"model": "MitchellSchaeffer"}, "fibres": {"direction": [1, 0, 0]},
      "conductivity": {"longitudinal": 0.1, "transverse": 0.01},
      "display": {"as": "points", "color": {"field": "V", "range": [-0.1, 0.05]}}}},
    "schedule": {"end": 1e-5}
  })",
                         registry);
  ASSERT_EQ(scene.display.size(), 1u);
  SceneDisplay display(*scene.kernel, scene.display, {});
  ASSERT_EQ(display.size(), 1u);
  FrameBuffers frame;
  display.Fill(0, frame);
  const SurfaceBuffers& out = frame.surfaces[0];
  ASSERT_EQ(out.primitive, Primitive::kPoints);
  ASSERT_EQ(out.num_vertices(), 12u);  // 3 x 2 x 2 grid nodes
  std::set<std::tuple<float, float, float>> nodes;
  for (std::size_t v = 0; v < 12; ++v)
    nodes.emplace(out.positions[3 * v], out.positions[3 * v + 1], out.positions[3 * v + 2]);
  for (float x : {0.0f, 0.001f, 0.002f})
    for (float y : {0.0f, 0.001f})
      for (float z : {0.0f, 0.001f}) EXPECT_EQ(nodes.count({x, y, z}), 1u) << x << y << z;
  EXPECT_EQ(out.range_lo, -0.1);
  EXPECT_EQ(out.range_hi, 0.05);
}

TEST(DrawSpec, SceneKeysChooseGeometryColourVisibilityAndTheCommandLineOverridesTheColour) {
  TypeRegistry registry;
  Scene scene = LoadText(BlockScene(R"({"as": "points", "visible": false, "size": 3,
      "color": {"field": "position", "component": "x", "map": "grey", "range": [0, 2]}})"),
                         registry);
  ASSERT_EQ(scene.display.size(), 1u);
  const DrawSpec& spec = scene.display[0].second;
  EXPECT_EQ(spec.as, Primitive::kPoints);
  EXPECT_FALSE(spec.visible);
  EXPECT_EQ(spec.size, 3.0f);
  EXPECT_EQ(spec.color.range, std::pair(0.0, 2.0));
  SceneDisplay display(*scene.kernel, scene.display, {});
  EXPECT_THAT(display.Hidden(), ElementsAre(true));
  FrameBuffers frame;
  display.Fill(0, frame);
  EXPECT_EQ(frame.surfaces[0].primitive, Primitive::kPoints);
  EXPECT_EQ(frame.surfaces[0].field, "position x");
  // --color block:position.z replaces the colour and keeps the rest of the scene's choice.
  ColorSpec z;
  z.field = "position";
  z.component = 2;
  SceneDisplay overridden(*scene.kernel, scene.display, {{"block", z}});
  overridden.Fill(0, frame);
  EXPECT_EQ(frame.surfaces[0].primitive, Primitive::kPoints);
  EXPECT_EQ(frame.surfaces[0].field, "position z");
  EXPECT_EQ(frame.surfaces[0].range_hi, 1.0);  // automatic: the override has no range
  EXPECT_THAT(overridden.Hidden(), ElementsAre(true));

  // A solid colour and the wireframe flag reach the buffers.
  TypeRegistry registry2;
  Scene solid =
      LoadText(BlockScene(R"({"wireframe": true, "color": {"color": [0, 0.5, 1]}})"), registry2);
  SceneDisplay solid_display(*solid.kernel, solid.display, {});
  solid_display.Fill(0, frame);
  EXPECT_EQ(frame.surfaces[0].primitive, Primitive::kTriangles);
  EXPECT_TRUE(frame.surfaces[0].wireframe);
  EXPECT_EQ(frame.surfaces[0].colors[0], 0.0f);
  EXPECT_EQ(frame.surfaces[0].colors[1], 0.5f);
  EXPECT_EQ(frame.surfaces[0].colors[2], 1.0f);
}

TEST(DrawSpec, BadDisplayKeysNameTheirJsonPath) {
  auto error = [](const std::string& display) {
    return testing::SceneLoadError(BlockScene(display));
  };
  EXPECT_THAT(error(R"({"as": "wires"})"), HasSubstr("scene.json: objects.block.display.as: "));
  EXPECT_THAT(error(R"({"size": 0})"),
              HasSubstr("scene.json: objects.block.display.size: expected a line width or point "
                        "size in pixels, in [1, 64]"));
  EXPECT_THAT(error(R"({"visible": "no"})"), HasSubstr("objects.block.display.visible"));
  EXPECT_THAT(error(R"({"colour": {}})"), HasSubstr("objects.block.display"));
  EXPECT_THAT(error(R"({"max_distance": 1})"),
              HasSubstr("objects.block.display.max_distance: only applies with a display 'mesh'"));
  EXPECT_THAT(error(R"({"color": {"field": "positon"}})"),
              HasSubstr("scene.json: objects.block.display.color: "));
  EXPECT_THAT(error(R"({"color": {"field": "positon"}})"), HasSubstr("position"));  // suggested
  EXPECT_THAT(error(R"({"color": {"field": "kinetic_energy"}})"),
              HasSubstr("objects.block.display.color: object 'block': display colour: field "
                        "'kinetic_energy' lives on globals"));
  EXPECT_THAT(error(R"({"as": "lines", "color": {"field": "reaction_force"}})"),
              HasSubstr("objects.block.display.color: object 'block': display colour: field "
                        "'reaction_force' lives on boundary vertices, but the object is drawn "
                        "as lines"));
  EXPECT_THAT(error(R"({"color": {"range": [1, 1]}})"),
              HasSubstr("objects.block.display.color.range: expected [lo, hi] with lo < hi"));
}

TEST(DrawSpec, AGeometryTheObjectLacksIsRejected) {
  auto chain = MakeChain();
  try {
    DisplayManager manager(*chain, DrawSpec{{}, Primitive::kTriangles});
    ADD_FAILURE() << "a surface was drawn for an object without one";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("object 'chain': display: it has no display surface"));
  }
  // A lumped circulation has no nodes at all.
  const std::string error = testing::SceneLoadError(R"({
    "objects": {"blood": {"type": "Circulation", "dt": 1e-3, "display": {"as": "points"},
      "compartments": {"arteries": {"type": "compliance", "compliance": 1e-8, "pressure": 1e4},
                       "veins": {"type": "reservoir", "pressure": 600}},
      "connections": {"out": {"type": "resistor", "from": "arteries", "to": "veins",
                              "resistance": 1e8}}}},
    "schedule": {"end": 1e-3}
  })");
  EXPECT_THAT(error, HasSubstr("scene.json: objects.blood.display.as: object 'blood': display: "
                               "it has no nodes to draw as points"));
}

}  // namespace
}  // namespace gipsi::viz
