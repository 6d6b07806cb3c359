// The scene loader's meshes for distributed runs: which objects are standalone (nothing else
// in the scene names them), which meshes it leaves to be made when their object asks, and the
// blocks it makes without the whole mesh (io/scene.h, core/registry.h).

#include <map>
#include <memory>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/test_objects.h"
#include "gipsi/base/error.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

// What the "Recorder" objects saw when they were built.
struct Seen {
  bool standalone = false;
  std::shared_ptr<const MeshBlock> block;  // when the object asked for block 1 of 3
};

// A registry whose "Recorder" objects take their domain whole, or as block 1 of 3 ("blocks":
// true), and record what the loader told them. "note" may name anything.
std::unique_ptr<TypeRegistry> RecordingRegistry(std::map<std::string, Seen>& seen, bool in_blocks) {
  auto registry = std::make_unique<TypeRegistry>();
  RegisterBuiltins(*registry);
  registry->meshes_in_blocks = in_blocks;
  registry->objects.Register(
      "Recorder",
      [&seen](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        ctx.CheckKeys({"blocks", "note"});
        Seen& s = seen[ctx.name];
        s.standalone = ctx.standalone;
        if (ctx.params.Bool("blocks", false))
          s.block = std::make_shared<MeshBlock>(ctx.DomainMeshBlock(1, 3));
        else
          (void)ctx.DomainMesh();
        return std::make_unique<testing::CountingObject>(ctx.name);
      },
      "records what the scene loader gives it");
  return registry;
}

const char* kScene = R"({
  "meshes": {
    "slab": {"generate": "box", "min": [0, 0, 0], "max": [2, 1, 1], "cells": [4, 3, 2],
             "scale": 0.01, "translate": [1, 2, 3]},
    "shared": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [1, 1, 1]},
    "unused": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [2, 1, 1]}
  },
  "objects": {
    "a": {"type": "Recorder", "domain": "slab", "dt": 0.001, "blocks": true},
    "b": {"type": "Recorder", "domain": "shared", "dt": 0.001},
    "c": {"type": "Recorder", "domain": "shared", "dt": 0.001, "note": "b.value"}
  },
  "probes": {"a_value": {"object": "a", "field": "value"}},
  "schedule": {"end": 0.01, "dt": 0.001, "order": ["c", "b", "a"]}
})";

// An object named by another object is not standalone; one only probes and the schedule's
// order name is. A distributed run's loader makes a standalone object's own mesh in blocks: the
// box's block (scaled and translated) is BlockOfMesh's of the whole box, and the whole box is
// never built; the meshes that other objects share, and those nobody uses, are built whole.
TEST(SceneMeshes, AStandaloneObjectsMeshIsMadeInBlocksWithoutTheWholeMesh) {
  std::map<std::string, Seen> seen;
  auto registry = RecordingRegistry(seen, true);
  Scene scene = LoadSceneFromString(kScene, "scene.json", ".", *registry);
  EXPECT_TRUE(seen["a"].standalone);
  EXPECT_FALSE(seen["b"].standalone);  // "c" names it
  EXPECT_TRUE(seen["c"].standalone);
  EXPECT_EQ(scene.meshes.count("slab"), 0U);
  EXPECT_EQ(scene.meshes.count("shared"), 1U);
  EXPECT_EQ(scene.meshes.count("unused"), 1U);

  Mesh whole = MakeTetBox(Vec3::Zero(), Vec3(2, 1, 1), {4, 3, 2});
  whole.Transform(0.01, Vec3(1, 2, 3));
  const MeshBlock expected = BlockOfMesh(whole, 1, 3);
  ASSERT_TRUE(seen["a"].block);
  const MeshBlock& block = *seen["a"].block;
  EXPECT_EQ(block.rank, 1);
  EXPECT_EQ(block.size, 3);
  EXPECT_EQ(block.num_nodes, whole.num_nodes());
  EXPECT_EQ(block.num_tets, whole.num_tets());
  EXPECT_EQ(block.num_triangles, whole.num_triangles());
  ASSERT_EQ(block.nodes.cols(), expected.nodes.cols());
  EXPECT_LT((block.nodes - expected.nodes).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(block.tets, expected.tets);
}

// A serial run builds every mesh whole, as before; the objects still learn they are standalone,
// and a block is then cut from the whole mesh.
TEST(SceneMeshes, ASerialRunBuildsEveryMeshWhole) {
  std::map<std::string, Seen> seen;
  auto registry = RecordingRegistry(seen, false);
  Scene scene = LoadSceneFromString(kScene, "scene.json", ".", *registry);
  EXPECT_TRUE(seen["a"].standalone);
  EXPECT_FALSE(seen["b"].standalone);
  EXPECT_EQ(scene.meshes.size(), 3U);
  ASSERT_TRUE(seen["a"].block);
  const MeshBlock expected = BlockOfMesh(*scene.meshes.at("slab"), 1, 3);
  EXPECT_EQ(seen["a"].block->nodes, expected.nodes);
  EXPECT_EQ(seen["a"].block->tets, expected.tets);
}

// A mistake in a mesh made in blocks is named by its JSON path, as when it is built whole, and
// so is one in a mesh nobody asks for.
TEST(SceneMeshes, AMistakeInAMeshMadeInBlocksNamesItsPath) {
  std::map<std::string, Seen> seen;
  auto registry = RecordingRegistry(seen, true);
  std::string text = kScene;
  auto load = [&](const std::string& from, const std::string& to) {
    std::string changed = text;
    changed.replace(changed.find(from), from.size(), to);
    try {
      (void)LoadSceneFromString(changed, "scene.json", ".", *registry);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(load("\"cells\": [4, 3, 2]", "\"cells\": [4, 0, 2]"),
              HasSubstr("meshes.slab.cells: expected an array of 3 integers in [1, 1000]"));
  EXPECT_THAT(load("\"scale\": 0.01", "\"scale\": -1"), HasSubstr("meshes.slab.scale"));
  EXPECT_THAT(load("\"translate\": [1, 2, 3]}", "\"translate\": [1, 2, 3], \"colour\": 1}"),
              HasSubstr("meshes.slab: unknown key 'colour'"));
  EXPECT_THAT(load("\"cells\": [2, 1, 1]", "\"cells\": [2, 1]"), HasSubstr("meshes.unused.cells"));
}

}  // namespace
}  // namespace gipsi
