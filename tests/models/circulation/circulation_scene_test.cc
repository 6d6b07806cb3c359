// The circulation scenes through the real `gipsi` tool: they validate, run, log valve events
// and write their probe CSVs; and the preset can be patched from a scene.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "apps/cli_test_util.h"
#include "models/circulation/circulation_test_util.h"
#include "test_paths.h"

namespace gipsi {
namespace {

using testing::Gipsi;
using ::testing::HasSubstr;
using testing::TempDir;

std::string ScenePath(const std::string& name) {
  return std::string(GIPSI_SOURCE_DIR) + "/scenes/" + name;
}

std::string ReadFile(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(CirculationScenes, ValidateAndListTheirFields) {
  for (const char* name : {"circulation_windkessel.json", "circulation_closed_loop.json"}) {
    const auto r = Gipsi("validate " + ScenePath(name));
    EXPECT_EQ(r.code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("Circulation"));
  }
  const auto r = Gipsi("validate " + ScenePath("circulation_closed_loop.json"));
  EXPECT_THAT(r.output, HasSubstr("lv_pressure"));
  EXPECT_THAT(r.output, HasSubstr("aortic_open"));
  EXPECT_THAT(r.output, HasSubstr("total_volume"));
}

// Two beats of the closed loop: the log names each valve transition with its time, and the
// probe CSVs hold the PV-loop columns with one row per millisecond (t = 0 included).
TEST(CirculationScenes, ClosedLoopRunLogsValveEventsAndWritesProbes) {
  const auto out = TempDir("gipsi_circulation_", "closed_loop");
  const auto r = Gipsi("run " + ScenePath("circulation_closed_loop.json") + " --until 1.6 --out " +
                       out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("blood: t = "));
  EXPECT_THAT(r.output, HasSubstr("valve aortic opens"));
  EXPECT_THAT(r.output, HasSubstr("valve mitral closes"));
  const std::string pv = ReadFile(out / "probes" / "pv.csv");
  EXPECT_THAT(pv, HasSubstr("time,lv_pressure,lv_volume,aorta_pressure"));
  std::size_t rows = 0;
  for (char ch : pv) rows += ch == '\n';
  EXPECT_EQ(rows, 1u + 1601u);  // header + t = 0, 1 ms, ..., 1.6 s
  EXPECT_TRUE(std::filesystem::exists(out / "probes" / "valves.csv"));
}

TEST(CirculationScenes, WindkesselRunWritesPressures) {
  const auto out = TempDir("gipsi_circulation_", "windkessel");
  const auto r = Gipsi("run -q " + ScenePath("circulation_windkessel.json") +
                       " --until 0.8 --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(ReadFile(out / "probes" / "windkessel.csv"),
              HasSubstr("time,arteries_pressure,ejection_pressure_drop,ejection_flow"));
}

// The scene patches the preset (RFC 7386): one parameter changed, the LV switched to a
// volume-driven chamber by one key (its elastance keys are then unused), a compartment removed
// with its connections re-routed.
TEST(CirculationScenes, ScenePatchesThePreset) {
  SceneHolder holder(R"({
    "objects": {"blood": {"type": "Circulation", "preset": "closed_loop", "dt": "1 ms",
      "compartments": {"aorta": {"compliance": "2 mL/mmHg"},
                       "lv": {"driven_by": "volume"}}}},
    "schedule": {"end": "0.1 s"}})");
  Circulation& blood = holder.Object("blood");
  const int aorta = blood.FindCompartment("aorta");
  EXPECT_NEAR(blood.circuit().compartments()[aorta].compliance, 2 * kMl / kMmHg, 1e-20);
  EXPECT_EQ(blood.circuit().compartments()[blood.FindCompartment("lv")].drive,
            CompartmentSpec::Drive::kVolume);
  EXPECT_TRUE(blood.TryFindField("lv_cavity_volume").has_value());
  EXPECT_FALSE(blood.TryFindField("lv_elastance").has_value());
  EXPECT_THAT(SceneError(R"({
    "objects": {"blood": {"type": "Circulation", "preset": "closed_loop",
      "compartments": {"veins": null}}},
    "schedule": {"end": "0.1 s"}})"),
              HasSubstr("preset closed_loop patched by the scene): "
                        "objects.blood.connections.peripheral.to: unknown compartment 'veins'"));
}

}  // namespace
}  // namespace gipsi
