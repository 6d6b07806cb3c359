// The scene snippets of docs/visualization.md and the display/probe snippets of
// docs/scene-format.md must work: a user copies them.

#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/display_manager.h"
#include "test_paths.h"

namespace gipsi::viz {
namespace {

std::string ReadSource(const std::string& file) {
  std::ifstream in(std::string(GIPSI_SOURCE_DIR) + "/" + file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The bodies of the ```json blocks of a markdown file.
std::vector<std::string> JsonBlocks(const std::string& markdown_file) {
  const std::string s = ReadSource(markdown_file);
  std::vector<std::string> blocks;
  const std::string open = "```json\n", close = "```";
  for (auto pos = s.find(open); pos != std::string::npos; pos = s.find(open, pos)) {
    pos += open.size();
    const auto end = s.find(close, pos);
    blocks.push_back(s.substr(pos, end - pos));
  }
  return blocks;
}

TEST(DocsVisualization, EveryCompleteSceneLoadsDrawsAndRuns) {
  int scenes = 0;
  for (const auto& block : JsonBlocks("docs/visualization.md")) {
    if (block.find("\"objects\"") == std::string::npos) continue;
    ++scenes;
    TypeRegistry registry;
    RegisterBuiltins(registry);
    Scene scene = LoadSceneFromString(block, "visualization.md", GIPSI_SOURCE_DIR, registry);
    SceneDisplay display(*scene.kernel, scene.display, {});
    FrameBuffers frame;
    display.Fill(0, frame);
    EXPECT_FALSE(frame.surfaces.empty());
    const RunResult result = scene.kernel->Run(0.002);
    EXPECT_TRUE(result.ok()) << result.diagnostic;
  }
  EXPECT_GE(scenes, 1);
}

// The probe and display snippets of scene-format.md are fragments about the Niederer slab's
// "tissue": they are put into scenes/slab_ep_grid_0.5mm.json in place of its own.
TEST(DocsVisualization, SceneFormatProbeAndDisplaySnippetsLoadIntoTheSlab) {
  const nlohmann::json slab = nlohmann::json::parse(ReadSource("scenes/slab_ep_grid_0.5mm.json"));
  int used = 0;
  for (const auto& block : JsonBlocks("docs/scene-format.md")) {
    if (block.find("\"line\"") == std::string::npos) continue;
    ++used;
    nlohmann::json scene = slab;
    scene["probes"] = nlohmann::json::parse("{" + block + "}")["probes"];
    TypeRegistry registry;
    RegisterBuiltins(registry);
    const Scene loaded =
        LoadSceneFromString(scene.dump(), "scene-format.md", GIPSI_SOURCE_DIR, registry);
    EXPECT_EQ(loaded.probes.size(), 2u);
  }
  EXPECT_EQ(used, 1);
}

}  // namespace
}  // namespace gipsi::viz
