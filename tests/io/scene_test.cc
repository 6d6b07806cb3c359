#include "gipsi/io/scene.h"

#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"
#include "gipsi/models/mass_spring/mass_spring.h"
#include "io/scene_test_util.h"
#include "temp_dir.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

/// A valid scene; tests replace parts of it to make it invalid.
std::string SceneText(const std::string& object_extra = "", const std::string& top_extra = "") {
  return R"({
  "meshes": {"box": {"generate": "box", "min": [0,0,0], "max": [0.1,0.1,0.1], "cells": [2,2,2]}},
  "objects": {
    "cube": {"type": "MassSpring", "domain": "box", "dt": 0.0001, "stiffness": 100)" +
         object_extra + R"(,
             "boundary_conditions": [{"name": "top", "region": {"group": "zmax"}, "fix": true}]}
  },
  "schedule": {"end": 0.01, "dt": 0.001})" +
         top_extra + "\n}";
}

std::string LoadError(const std::string& text) { return testing::SceneLoadError(text); }

Scene Load(const std::string& text) {
  static TypeRegistry* registry = [] {
    auto* r = new TypeRegistry;
    RegisterBuiltins(*r);
    return r;
  }();
  return LoadSceneFromString(text, "scene.json", ".", *registry);
}

TEST(Scene, LoadsObjectsConditionsAndSchedule) {
  Scene scene = Load(SceneText());
  EXPECT_EQ(scene.end_time, 0.01);
  EXPECT_EQ(scene.kernel->macro_dt(), 0.001);
  EXPECT_EQ(scene.kernel->coordinator().object_substeps(0), 10);
  const auto& bc = scene.boundary_conditions.at("cube/top");
  EXPECT_EQ(bc.vertices.size(), 9u);  // 3x3 nodes on the top face
  const SimObject& cube = scene.kernel->FindObject("cube");
  EXPECT_EQ(cube.boundary_conditions().kind(bc.vertices[0], 2), ConstraintKind::kDisplacement);
}

TEST(Scene, KeepsObjectsInFileOrder) {
  // The default schedule steps objects in declaration order, so the file order must survive.
  Scene scene = Load(R"({
    "meshes": {"box": {"generate": "box", "min": [0,0,0], "max": [1,1,1], "cells": [1,1,1]}},
    "objects": {"zeta": {"type": "MassSpring", "domain": "box", "dt": 0.001},
                "alpha": {"type": "MassSpring", "domain": "box", "dt": 0.001}},
    "schedule": {"end": 0.01}})");
  EXPECT_EQ(scene.kernel->coordinator().object(0).name(), "zeta");
  EXPECT_EQ(scene.kernel->coordinator().object(1).name(), "alpha");
}

TEST(Scene, RunsAndHoldsFixedVertices) {
  Scene scene = Load(SceneText());
  ASSERT_TRUE(scene.kernel->Run(scene.end_time).ok());
  const auto& cube = static_cast<const MassSpring&>(scene.kernel->FindObject("cube"));
  for (int v : scene.boundary_conditions.at("cube/top").vertices) {
    int node = cube.boundary().vertex_to_node[static_cast<std::size_t>(v)];
    EXPECT_EQ(cube.domain_positions().col(node), cube.domain().nodes.col(node));
  }
  // Everything else sagged.
  EXPECT_LT(cube.domain_positions().row(2).minCoeff(), -1e-6);
}

TEST(SceneErrors, MalformedJsonGivesLineAndColumn) {
  EXPECT_THAT(LoadError("{\n  \"objects\": {,\n}"),
              HasSubstr("scene.json: line 2, column 15: invalid JSON: syntax error while parsing "
                        "object key - unexpected ','; expected string literal"));
}

TEST(SceneErrors, UnknownTypeSuggestsTheClosest) {
  std::string text = SceneText();
  text.replace(text.find("\"MassSpring\""), 12, "\"MassSprign\"");
  // The list of known types grows with every model; check its start and a few members.
  const std::string error = LoadError(text);
  EXPECT_THAT(error, HasSubstr("scene.json: objects.cube.type: unknown object type 'MassSprign' "
                               "(did you mean 'MassSpring'?); known: Aggregate, "));
  for (const char* type : {"FemSolid", "MassSpring", "Monodomain"})
    EXPECT_THAT(error, HasSubstr(type));
}

TEST(SceneErrors, WrongParameterTypeNamesThePath) {
  std::string text = SceneText();
  text.replace(text.find("\"stiffness\": 100"), 16, "\"stiffness\": \"abc\"");
  EXPECT_EQ(LoadError(text),
            "scene.json: objects.cube.stiffness: expected a positive number, got \"abc\"");
}

TEST(SceneErrors, AndersonDepthIsAnIntegerUpToEight) {
  std::string text = SceneText();
  text.replace(text.find("\"MassSpring\""), 12, "\"FemSolid\"");
  text.replace(text.find("\"stiffness\": 100"), 16,
               R"("material": {"law": "NeoHookean", "youngs_modulus": 1000, "poisson_ratio": 0.3},
                  "newton": {"reuse_factorization": true, "anderson": 9})");
  EXPECT_EQ(LoadError(text),
            "scene.json: objects.cube.newton.anderson: expected an integer in [0, 8] (0: off), "
            "got 9");
}

TEST(SceneErrors, NonFiniteParameterIsRejected) {
  // JSON has no NaN literal; an overflowing literal is the way a non-finite value sneaks in,
  // and the parser refuses it before any parameter sees it.
  EXPECT_THAT(LoadError(SceneText(", \"damping\": 1e999")),
              HasSubstr("scene.json: invalid JSON: number overflow parsing '1e999'"));
}

TEST(SceneErrors, NegativeParameterIsRejected) {
  EXPECT_EQ(LoadError(SceneText(", \"density\": -5")),
            "scene.json: objects.cube.density: expected a positive number, got -5");
}

TEST(SceneErrors, UnknownMaterialLawSuggestsTheClosest) {
  EXPECT_THAT(LoadError(SceneText(R"(, "material": {"law": "Exponentail", "b": 5})")),
              HasSubstr("objects.cube.material.law: unknown material law 'Exponentail' (did you "
                        "mean 'Exponential'?); known: Corotational, Exponential, Guccione, Hooke, "
                        "Linear, NeoHookean, StVenantKirchhoff"));
  EXPECT_THAT(LoadError(SceneText(R"(, "material": {"law": "Exponential"})")),
              HasSubstr("objects.cube.material: missing required key 'b'"));
}

TEST(SceneErrors, UnknownKeyIsATypo) {
  EXPECT_THAT(LoadError(SceneText(", \"gravty\": [0,0,-9.81]")),
              HasSubstr("objects.cube: unknown key 'gravty' (did you mean 'gravity'?)"));
}

TEST(SceneErrors, MissingMeshFileNamesTheFile) {
  std::string text = SceneText();
  text.replace(text.find("{\"generate\": \"box\""), 0, "{\"file\": \"nope/missing.msh\"}, \"x\": ");
  EXPECT_THAT(LoadError(text), HasSubstr("meshes.box.file: "));
  EXPECT_THAT(LoadError(text), HasSubstr("missing.msh"));
}

TEST(SceneErrors, MeshWithOutOfRangeIndexIsRejected) {
  const auto dir = testing::TempDir("gipsi_scene_", "bad_index");
  {
    std::ofstream f(dir / "bad.msh");
    f << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
         "$EndNodes\n$Elements\n1\n1 4 0 1 2 3 9\n$EndElements\n";
  }
  TypeRegistry registry;
  RegisterBuiltins(registry);
  std::string text = R"({"meshes": {"m": {"file": "bad.msh"}},
    "objects": {"o": {"type": "MassSpring", "domain": "m", "dt": 0.001}},
    "schedule": {"end": 1}})";
  try {
    (void)LoadSceneFromString(text, "scene.json", dir, registry);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("meshes.m.file"));
    EXPECT_THAT(e.what(), HasSubstr("bad.msh"));
  }
}

TEST(SceneErrors, RegionThatSelectsNothingIsAnError) {
  std::string text = SceneText();
  text.replace(text.find("{\"group\": \"zmax\"}"), 17,
               "{\"box\": {\"min\": [5,5,5], \"max\": [6,6,6]}}");
  EXPECT_THAT(LoadError(text), HasSubstr("objects.cube.boundary_conditions[0]: the region "
                                         "selects no boundary vertex of object 'cube'"));
}

TEST(SceneErrors, UnknownGroupListsTheGroups) {
  std::string text = SceneText();
  text.replace(text.find("\"zmax\""), 6, "\"top\"");
  EXPECT_THAT(LoadError(text), HasSubstr("objects.cube.boundary_conditions[0].region"));
  EXPECT_THAT(LoadError(text), HasSubstr("zmax"));
}

TEST(SceneErrors, TimeStepMustDivideMacroStep) {
  std::string text = SceneText();
  text.replace(text.find("\"dt\": 0.0001"), 12, "\"dt\": 0.0003");
  EXPECT_THAT(LoadError(text), HasSubstr("object 'cube': its time step 0.0003 s does not divide"));
}

TEST(SceneErrors, EventRemovingUnknownConditionIsAnError) {
  EXPECT_THAT(LoadError(SceneText("", "").replace(
                  SceneText().find("\"schedule\": {\"end\": 0.01, \"dt\": 0.001}"), 38,
                  "\"schedule\": {\"end\": 0.01, \"dt\": 0.001, \"events\": [{\"at\": "
                  "0.005, \"object\": \"cube\", \"remove\": \"bottom\"}]}")),
              HasSubstr("schedule.events[0].remove: object 'cube' has no boundary condition named "
                        "'bottom'"));
}

TEST(SceneErrors, ProbeOutsideTheDomainIsAnError) {
  EXPECT_THAT(LoadError(SceneText("", R"(, "probes": {"p": {"object": "cube", "point": [1, 1, 1],
                                       "fields": ["displacement"]}})")),
              HasSubstr("probes.p.point: the point lies"));
}

TEST(Scene, EventReleasesConditionAtItsTime) {
  std::string text = SceneText();
  text.replace(text.find("\"schedule\": {\"end\": 0.01, \"dt\": 0.001}"), 38,
               R"("schedule": {"end": 0.01, "dt": 0.001,
                   "events": [{"at": 0.005, "object": "cube", "remove": "top"}]})");
  Scene scene = Load(text);
  const SimObject& cube = scene.kernel->FindObject("cube");
  ASSERT_TRUE(scene.kernel->Run(0.005).ok());
  EXPECT_TRUE(cube.boundary_conditions().any_constraint());
  ASSERT_TRUE(scene.kernel->Run(0.006).ok());
  EXPECT_FALSE(cube.boundary_conditions().any_constraint());
}

// A probe's name becomes a file name under <out>/probes/: names that would climb out of that
// folder are refused.
TEST(Scene, ProbeNamesCannotLeaveTheOutputDirectory) {
  for (const char* name : {"../escape", "a/b", ".hidden", ""}) {
    const std::string probes = std::string(R"(, "probes": {")") + name +
                               R"(": {"object": "cube", "fields": ["kinetic_energy"]}})";
    EXPECT_THAT(LoadError(SceneText("", probes)), HasSubstr("must be a plain file name")) << name;
  }
}

/// The box of SceneText written out in the scene: its nodes (%.17g round-trips exactly) and
/// tets as JSON arrays.
std::string InlineBox(const Mesh& box) {
  std::string nodes, tets;
  for (Index i = 0; i < box.num_nodes(); ++i)
    nodes += fmt::format("{}[{:.17g}, {:.17g}, {:.17g}]", i ? ", " : "", box.nodes(0, i),
                         box.nodes(1, i), box.nodes(2, i));
  for (Index e = 0; e < box.num_tets(); ++e)
    tets += fmt::format("{}[{}, {}, {}, {}]", e ? ", " : "", box.tets(0, e), box.tets(1, e),
                        box.tets(2, e), box.tets(3, e));
  return fmt::format(R"({{"nodes": [{}], "tets": [{}]}})", nodes, tets);
}

TEST(Scene, AMeshGivenByItsNodesAndTetsRunsAsTheSameMeshGenerated) {
  Scene generated = Load(SceneText());
  const Mesh& box = *generated.meshes.at("box");
  std::string text = SceneText();
  const std::size_t start = text.find("{\"generate\": \"box\"");
  text.replace(start, text.find('}', start) + 1 - start, InlineBox(box));
  // The fixed boundary condition selects the generated box's group "zmax"; the inline mesh has
  // no groups, so select the same face by a box region.
  text.replace(text.find(R"({"group": "zmax"})"), std::string(R"({"group": "zmax"})").size(),
               R"({"box": {"min": [-1, -1, 0.0999], "max": [1, 1, 1]}})");
  Scene inline_scene = Load(text);
  const Mesh& mesh = *inline_scene.meshes.at("box");
  EXPECT_EQ(mesh.nodes, box.nodes);
  EXPECT_EQ(mesh.tets, box.tets);
  ASSERT_TRUE(generated.kernel->Run(0.005).ok());
  ASSERT_TRUE(inline_scene.kernel->Run(0.005).ok());
  EXPECT_EQ(inline_scene.kernel->FindObject("cube").domain_positions(),
            generated.kernel->FindObject("cube").domain_positions());
}

TEST(SceneErrors, AMeshGivenByItsNodesNamesTheBadValueByItsPath) {
  auto scene = [](const std::string& mesh) {
    return R"({"meshes": {"m": )" + mesh + R"(},
      "objects": {"o": {"type": "MassSpring", "domain": "m", "dt": 0.001}},
      "schedule": {"end": 1}})";
  };
  const std::string nodes = R"("nodes": [[0,0,0], [1,0,0], [0,1,0], [0,0,1]])";
  EXPECT_THAT(LoadError(scene("{" + nodes + R"(, "tets": [[0,1,2,3], [0,1,2,4]]})")),
              HasSubstr("meshes.m.tets[1][3]: expected a node index in [0, 3] (0-based), got 4"));
  EXPECT_THAT(LoadError(scene("{" + nodes + R"(, "tets": [[0,1,2]]})")),
              HasSubstr("meshes.m.tets[0]: expected 4 node indices"));
  EXPECT_THAT(LoadError(scene("{" + nodes + R"(, "triangles": [[0,1,-1]]})")),
              HasSubstr("meshes.m.triangles[0][2]: expected a node index in [0, 3]"));
  EXPECT_THAT(LoadError(scene(R"({"nodes": [[0,0,0], [1,0], [0,1,0]], "triangles": [[0,1,2]]})")),
              HasSubstr("meshes.m.nodes[1]: expected"));
  EXPECT_THAT(LoadError(scene("{" + nodes + "}")),
              HasSubstr("meshes.m: a mesh given by its 'nodes' needs 'tets' or 'triangles' too"));
  EXPECT_THAT(
      LoadError(scene(R"({"nodes": [], "tets": []})")),
      HasSubstr("meshes.m.nodes: expected a non-empty array of [x, y, z] node coordinates"));
  EXPECT_THAT(LoadError(scene(R"({"file": "a.msh", "tets": [[0,1,2,3]]})")),
              HasSubstr("meshes.m.tets: only a mesh given by its 'nodes' takes this key"));
  EXPECT_THAT(LoadError(scene("{" + nodes + R"(, "tets": [[0,1,2,3]], "file": "a.msh"})")),
              HasSubstr("meshes.m: expected exactly one of 'file', 'generate', 'nodes'"));
}

TEST(SceneErrors, OnlyTheGmshShellGeneratorsTakeAnOrder) {
  auto scene = [](const std::string& mesh) {
    return R"({"meshes": {"m": )" + mesh + R"(},
      "objects": {"o": {"type": "MassSpring", "domain": "m", "dt": 0.001}},
      "schedule": {"end": 1}})";
  };
  EXPECT_THAT(LoadError(scene(R"({"generate": "box", "min": [0,0,0], "max": [1,1,1],
                                  "cells": [1,1,1], "order": 2})")),
              HasSubstr("meshes.m.order: only the generators \"ellipsoid_shell\" and "
                        "\"cylinder_shell\" take 'order'"));
  EXPECT_THAT(LoadError(scene(R"({"generate": "cylinder_shell", "inner_radius": 1,
                                  "outer_radius": 2, "height": 1, "size": 0.5, "order": 3})")),
              HasSubstr("meshes.m.order: expected 1 (linear tets) or 2 (second order), got 3"));
}

}  // namespace
}  // namespace gipsi
