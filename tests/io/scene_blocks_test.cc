// The scene loader's meshes for distributed runs: which objects may be made in blocks (nothing
// else in the scene names them but connectors coupling their parts), which meshes it leaves to
// be made when their object asks, and the blocks it makes without the whole mesh (io/scene.h,
// core/registry.h).

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/test_objects.h"
#include "gipsi/base/error.h"
#include "gipsi/base/json_node.h"
#include "gipsi/core/in_blocks.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/mesh_io.h"
#include "gipsi/io/scene.h"
#include "temp_dir.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

// What the "Recorder" objects saw when they were built.
struct Seen {
  bool in_blocks = false;
  std::shared_ptr<const MeshBlock> block;  // when the object asked for block 1 of 3
};

// A registry whose "Recorder" objects take their domain whole, or as block 1 of 3 ("blocks":
// true), and record what the loader told them. "note" may name anything. In a distributed run
// (`in_blocks`) a Recorder may be made in blocks unless it says "whole": true. Its "Reader"
// and "Glance" connectors are FieldCopies under other names: the loader takes a Reader to need
// its objects whole, and a Glance to read only global fields (as a CavityCoupling does).
std::unique_ptr<TypeRegistry> RecordingRegistry(std::map<std::string, Seen>& seen, bool in_blocks) {
  auto registry = std::make_unique<TypeRegistry>();
  RegisterBuiltins(*registry);
  registry->meshes_in_blocks = in_blocks;
  if (in_blocks)
    registry->splits_in_blocks["Recorder"] = [](const JsonNode& params) {
      return !params.Bool("whole", false);
    };
  const ConnectorFactory* copy = registry->connectors.Find("FieldCopy");
  registry->connectors.Register("Reader", *copy, "a FieldCopy the loader does not know");
  registry->connectors.Register("Glance", *copy, "a FieldCopy of global fields");
  registry->connector_part_use["Glance"] = [](const JsonNode&) {
    return TypeRegistry::PartUse::kGlobal;
  };
  registry->objects.Register(
      "Recorder",
      [&seen](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        ctx.CheckKeys({"blocks", "note", "whole"});
        Seen& s = seen[ctx.name];
        s.in_blocks = ctx.in_blocks;
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

// An object named by another object is not made in blocks; one only probes and the schedule's
// order name is. A distributed run's loader makes such an object's own mesh in blocks: the
// box's block (scaled and translated) is BlockOfMesh's of the whole box, and the whole box is
// never built; the meshes that other objects share, and those nobody uses, are built whole.
TEST(SceneMeshes, AnObjectOnlyProbesReadIsMadeInBlocksWithoutTheWholeMesh) {
  std::map<std::string, Seen> seen;
  auto registry = RecordingRegistry(seen, true);
  Scene scene = LoadSceneFromString(kScene, "scene.json", ".", *registry);
  EXPECT_TRUE(seen["a"].in_blocks);
  EXPECT_FALSE(seen["b"].in_blocks);  // "c" names it
  EXPECT_TRUE(seen["c"].in_blocks);
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

// A TetGen mesh of an object made in blocks is read in blocks too (every process streams the
// files and keeps its block): the block, scaled and translated, is the whole mesh's, and the
// whole mesh is never built.
TEST(SceneMeshes, ATetGenMeshIsReadInBlocks) {
  const std::filesystem::path dir = gipsi::testing::TestTempDir();
  std::ofstream(dir / "pair.node") << "5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n";
  std::ofstream(dir / "pair.ele") << "2 4 1\n1 1 2 3 4 7\n2 2 3 4 5 8\n";
  std::map<std::string, Seen> seen;
  auto registry = RecordingRegistry(seen, true);
  const std::string text = R"({
    "meshes": {"pair": {"file": "pair.ele", "scale": 0.01, "translate": [1, 2, 3]}},
    "objects": {"a": {"type": "Recorder", "domain": "pair", "dt": 0.001, "blocks": true}},
    "schedule": {"end": 0.01, "dt": 0.001}
  })";
  Scene scene = LoadSceneFromString(text, "scene.json", dir, *registry);
  EXPECT_TRUE(seen["a"].in_blocks);
  EXPECT_EQ(scene.meshes.count("pair"), 0U);
  Mesh whole = ReadMesh(dir / "pair.node");
  whole.Transform(0.01, Vec3(1, 2, 3));
  const MeshBlock expected = BlockOfMesh(whole, 1, 3);
  ASSERT_TRUE(seen["a"].block);
  const MeshBlock& block = *seen["a"].block;
  EXPECT_EQ(block.num_nodes, 5);
  EXPECT_EQ(block.num_tets, 2);
  ASSERT_EQ(block.nodes.cols(), expected.nodes.cols());
  EXPECT_LT((block.nodes - expected.nodes).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(block.tets, expected.tets);
  ASSERT_EQ(block.groups.size(), 2U);  // region_7 and region_8, on every block
  EXPECT_EQ(block.groups[1].name, "region_8");
  EXPECT_EQ(block.groups[1].items, expected.groups[1].items);
}

// A serial run builds every mesh whole and makes nothing in blocks; a block asked for is then cut
// from the whole mesh.
TEST(SceneMeshes, ASerialRunBuildsEveryMeshWhole) {
  std::map<std::string, Seen> seen;
  auto registry = RecordingRegistry(seen, false);
  Scene scene = LoadSceneFromString(kScene, "scene.json", ".", *registry);
  EXPECT_FALSE(seen["a"].in_blocks);
  EXPECT_FALSE(seen["b"].in_blocks);
  EXPECT_EQ(scene.meshes.size(), 3U);
  ASSERT_TRUE(seen["a"].block);
  const MeshBlock expected = BlockOfMesh(*scene.meshes.at("slab"), 1, 3);
  EXPECT_EQ(seen["a"].block->nodes, expected.nodes);
  EXPECT_EQ(seen["a"].block->tets, expected.tets);
}

// Objects joined only by connectors that couple parts (FieldCopy) are made in blocks together
// when all of them can be and share one domain mesh, whose blocks they then ask for (it is never
// built whole); a "nearest" copy couples parts split any way. Another mesh (for an "auto"
// copy), an unknown connector, or an end that must be whole keeps every object such a connector
// joins whole, and through them the objects joined to those. A connector of global fields (Glance)
// joins an object made in blocks to a whole one. An event may name an object made in blocks (it
// sets the part's conditions and uniform field values).
TEST(SceneMeshes, ObjectsCoupledPartToPartAreMadeInBlocksTogether) {
  std::map<std::string, Seen> seen;
  auto registry = RecordingRegistry(seen, true);
  const char* scene_text = R"({
    "meshes": {
      "heart": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [2, 2, 2]},
      "slab": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [2, 1, 1]},
      "other": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [1, 1, 1]},
      "lone": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [1, 1, 3]}
    },
    "objects": {
      "ep": {"type": "Recorder", "domain": "heart", "dt": 0.001, "blocks": true},
      "muscle": {"type": "Recorder", "domain": "heart", "dt": 0.001, "blocks": true},
      "x": {"type": "Recorder", "domain": "slab", "dt": 0.001},
      "y": {"type": "Recorder", "domain": "other", "dt": 0.001},
      "p": {"type": "Recorder", "domain": "slab", "dt": 0.001},
      "q": {"type": "Recorder", "domain": "slab", "dt": 0.001},
      "r": {"type": "Recorder", "domain": "slab", "dt": 0.001},
      "s": {"type": "Recorder", "domain": "slab", "dt": 0.001},
      "t": {"type": "Recorder", "domain": "slab", "dt": 0.001, "whole": true},
      "u": {"type": "Recorder", "domain": "slab", "dt": 0.001},
      "v": {"type": "Recorder", "domain": "slab", "dt": 0.001},
      "w": {"type": "Recorder", "domain": "slab", "dt": 0.001},
      "g": {"type": "Recorder", "domain": "lone", "dt": 0.001, "blocks": true},
      "h": {"type": "Recorder", "domain": "slab", "dt": 0.001, "whole": true}
    },
    "connectors": {
      "ec": {"type": "FieldCopy", "from": "ep.value", "to": "muscle.value"},
      "across": {"type": "FieldCopy", "from": "x.value", "to": "y.value"},
      "pq": {"type": "FieldCopy", "from": "p.value", "to": "q.value"},
      "qr": {"type": "Reader", "from": "q.value", "to": "r.value"},
      "st": {"type": "FieldCopy", "from": "s.value", "to": "t.value"},
      "uv": {"type": "FieldCopy", "from": "u.value", "to": "v.value", "mapping": "nearest"},
      "gh": {"type": "Glance", "from": "g.value", "to": "h.value"}
    },
    "schedule": {"end": 0.002, "dt": 0.001,
                 "events": [{"at": 0.001, "object": "w", "set_field": {"field": "value",
                                                                        "value": [0, 0, 0]}}]}
  })";
  Scene scene = LoadSceneFromString(scene_text, "scene.json", ".", *registry);
  EXPECT_TRUE(seen["ep"].in_blocks);
  EXPECT_TRUE(seen["muscle"].in_blocks);
  EXPECT_TRUE(seen["g"].in_blocks);
  EXPECT_TRUE(seen["w"].in_blocks);
  EXPECT_TRUE(seen["u"].in_blocks);
  EXPECT_TRUE(seen["v"].in_blocks);
  for (const char* name : {"x", "y", "p", "q", "r", "s", "t", "h"})
    EXPECT_FALSE(seen[name].in_blocks) << name;
  ASSERT_TRUE(seen["ep"].block);
  ASSERT_TRUE(seen["muscle"].block);
  EXPECT_EQ(seen["ep"].block->tets, seen["muscle"].block->tets);
  EXPECT_EQ(seen["ep"].block->num_tets, 48);
  EXPECT_EQ(scene.meshes.count("heart"), 0U);  // only blocks of it were made
  EXPECT_EQ(scene.meshes.count("slab"), 1U);
}

// A barycentric or nearest FieldCopy (and an excitation–contraction, and a boundary coupling)
// couples parts split any way, so the objects it joins are made in blocks whatever their meshes,
// and whether or not its other end is: one on another mesh, one kept whole. A direct copy, or
// "auto" (which may turn out direct), still needs one mesh.
TEST(SceneMeshes, ABarycentricCopyLetsObjectsOnOtherMeshesBeMadeInBlocks) {
  std::map<std::string, Seen> seen;
  auto registry = RecordingRegistry(seen, true);
  const auto& use = registry->connector_part_use.at("FieldCopy");
  auto use_of = [&use](const char* text) {
    const JsonDocument doc = JsonDocument::Parse(text, "connector.json");
    return use(doc.root());
  };
  using PartUse = TypeRegistry::PartUse;
  EXPECT_EQ(use_of(R"({"type": "FieldCopy", "mapping": "barycentric"})"), PartUse::kAnyParts);
  EXPECT_EQ(use_of(R"({"type": "FieldCopy", "mapping": "direct"})"), PartUse::kPartToPart);
  EXPECT_EQ(use_of(R"({"type": "FieldCopy", "mapping": "auto"})"), PartUse::kPartToPart);
  EXPECT_EQ(use_of(R"({"type": "FieldCopy"})"), PartUse::kPartToPart);
  EXPECT_EQ(use_of(R"({"type": "FieldCopy", "mapping": "nearest"})"), PartUse::kAnyParts);
  const JsonDocument ec = JsonDocument::Parse(R"({"type": "ExcitationContraction"})", "ec.json");
  EXPECT_EQ(registry->connector_part_use.at("ExcitationContraction")(ec.root()),
            PartUse::kAnyParts);
  // A boundary coupling too: the driver's parts answer for the follower's interface vertices.
  const JsonDocument glue = JsonDocument::Parse(R"({"type": "BoundaryCoupling"})", "glue.json");
  EXPECT_EQ(registry->connector_part_use.at("BoundaryCoupling")(glue.root()), PartUse::kAnyParts);

  const JsonDocument doc = JsonDocument::Parse(R"({
    "objects": {
      "ep": {"type": "Recorder", "domain": "fine"},
      "muscle": {"type": "Recorder", "domain": "coarse"},
      "probe": {"type": "Recorder", "domain": "coarse"},
      "held": {"type": "Recorder", "domain": "fine", "whole": true},
      "a": {"type": "Recorder", "domain": "fine"},
      "b": {"type": "Recorder", "domain": "coarse"}
    },
    "connectors": {
      "ec": {"type": "FieldCopy", "from": "ep.V", "to": "muscle.tension",
             "mapping": "barycentric"},
      "back": {"type": "FieldCopy", "from": "held.V", "to": "probe.V", "mapping": "barycentric"},
      "ab": {"type": "FieldCopy", "from": "a.V", "to": "b.V"}
    }
  })",
                                               "scene.json");
  const JsonNode root = doc.root();
  const std::set<std::string> in_blocks =
      InBlocksObjects(root.At("objects"), root.Find("connectors"), *registry);
  EXPECT_EQ(in_blocks, (std::set<std::string>{"ep", "muscle", "probe"}));
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
