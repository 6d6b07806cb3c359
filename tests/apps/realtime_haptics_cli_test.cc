// `gipsi run` with a real-time haptic probe (scenes/liver_palpation_mouse.json: a Mouse device,
// which headless stays at its start): the loop runs with the simulation and its period
// percentiles are logged at the end; checkpoints and resuming are refused, naming the probe.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "apps/cli_test_util.h"
#include "test_paths.h"

namespace gipsi {
namespace {

namespace fs = std::filesystem;
using testing::Gipsi;
using ::testing::HasSubstr;
using testing::Result;
using testing::TempDir;

const std::string kScene = std::string(GIPSI_SOURCE_DIR) + "/scenes/liver_palpation_mouse.json";

TEST(GipsiRunRealtimeHaptics, RunsTheLoopWithTheSimulationAndLogsItsPeriods) {
  const fs::path out = TempDir("rt_haptics", "run");
  const Result r = Gipsi("run " + kScene + " --until 0.2 -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("haptic loop of 'probe': "));
  EXPECT_THAT(r.output, HasSubstr(" ticks at 1000 Hz; period p50 "));
  EXPECT_THAT(r.output, HasSubstr("p99.9 "));
  // The probe's fields were recorded: the tool rests at its start (no mouse) above the liver,
  // so there is no force.
  std::ifstream csv(out / "probes" / "tool.csv");
  std::string header, first;
  ASSERT_TRUE(std::getline(csv, header));
  EXPECT_THAT(header, HasSubstr("tool_force_z"));
  std::string line, last;
  while (std::getline(csv, line)) last = line;
  // time, tool_force (3), model_force, tool_position (3), proxy_position (3): exact values (the
  // start position is copied, never computed).
  std::vector<double> values;
  std::stringstream fields(last);
  for (std::string v; std::getline(fields, v, ',');) values.push_back(std::stod(v));
  ASSERT_EQ(values.size(), 11u) << last;
  const std::vector<double> expected = {0, 0, 0, 0, -0.0175, 0.0178, 0.034, -0.0175, 0.0178, 0.034};
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(values[i + 1], expected[i]) << i;
}

TEST(GipsiRunRealtimeHaptics, RefusesCheckpointsAndResuming) {
  const fs::path out = TempDir("rt_haptics", "checkpoint");
  Result r = Gipsi("run -q " + kScene + " --until 0.1 --checkpoint-every 0.05 -o " + out.string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output,
              HasSubstr("--checkpoint-every: the scene's HapticProbe 'probe' is real-time "
                        "(objects.probe.realtime): a real-time run is not deterministic"));
  r = Gipsi("run -q " + kScene + " --resume " + (out / "none.gck").string() + " -o " +
            out.string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr("--resume: the scene's HapticProbe 'probe' is real-time"));
}

}  // namespace
}  // namespace gipsi
