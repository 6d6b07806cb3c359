// The complete scenes shown in the README and docs/ must load: a user copies them.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "test_paths.h"

namespace gipsi {
namespace {

std::vector<std::string> CompleteSceneSnippets(const std::string& markdown_file) {
  std::ifstream in(std::string(GIPSI_SOURCE_DIR) + "/" + markdown_file);
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  std::vector<std::string> snippets;
  const std::string open = "```json\n", close = "```";
  for (auto pos = s.find(open); pos != std::string::npos; pos = s.find(open, pos)) {
    pos += open.size();
    auto end = s.find(close, pos);
    std::string body = s.substr(pos, end - pos);
    if (body.find("\"objects\"") != std::string::npos &&
        body.find("\"schedule\"") != std::string::npos)
      snippets.push_back(body);
  }
  return snippets;
}

TEST(DocsSnippets, EveryCompleteSceneInTheReadmeLoadsAndRuns) {
  auto snippets = CompleteSceneSnippets("README.md");
  ASSERT_FALSE(snippets.empty());
  for (const auto& snippet : snippets) {
    TypeRegistry registry;
    RegisterBuiltins(registry);
    Scene scene = LoadSceneFromString(snippet, "README.md", GIPSI_SOURCE_DIR, registry);
    RunResult result = scene.kernel->Run(0.01);
    EXPECT_TRUE(result.ok()) << result.diagnostic;
  }
}

}  // namespace
}  // namespace gipsi
