// End-to-end tests of the `gipsi` command-line tool: they run the real binary on scene files.

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "apps/cli_test_util.h"
#include "gipsi/core/registry.h"

#include "gipsi/io/vtu_reader.h"
#include "test_paths.h"

namespace gipsi {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using testing::Gipsi;
using testing::Result;

fs::path TempDir(const std::string& name) { return testing::TempDir("gipsi_cli_", name); }

std::string Scene(const std::string& name) {
  return std::string(GIPSI_SOURCE_DIR) + "/scenes/" + name;
}

std::vector<std::string> PvdFiles(const fs::path& pvd) {
  std::ifstream in(pvd);
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  EXPECT_THAT(s, HasSubstr("</VTKFile>"));  // complete document
  std::vector<std::string> files;
  const std::string key = "file=\"";
  for (auto pos = s.find(key); pos != std::string::npos; pos = s.find(key, pos)) {
    pos += key.size();
    auto end = s.find('"', pos);
    files.push_back(s.substr(pos, end - pos));
  }
  return files;
}

std::size_t CountLines(const fs::path& file) {
  std::ifstream in(file);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

TEST(GipsiRun, DemoSceneWritesReadablePvdAndProbeCsv) {
  fs::path out = TempDir("demo");
  Result r = Gipsi("run " + Scene("hanging_sheet.json") + " --until 0.2 --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("real-time factor:"));
  EXPECT_THAT(r.output, HasSubstr("sheet                MassSpring     1000 steps of 0.0002 s"));
  auto files = PvdFiles(out / "sheet.pvd");
  ASSERT_EQ(files.size(), 5u);  // t = 0, 0.05, ..., 0.2
  Mesh last = ReadVtu(out / files.back());
  EXPECT_EQ(last.num_nodes(), 441);
  EXPECT_EQ(last.num_triangles(), 800);
  // 0 to 0.2 s every 0.01 s: 21 rows and a header.
  EXPECT_EQ(CountLines(out / "probes" / "centre.csv"), 22u);
  std::ifstream csv(out / "probes" / "centre.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "time,displacement_x,displacement_y,displacement_z");
}

TEST(GipsiRun, LiverSceneWritesEmbeddedDisplaySurface) {
  fs::path out = TempDir("liver");
  Result r = Gipsi("run -q " + Scene("hanging_liver.json") + " --until 0.02 --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  auto files = PvdFiles(out / "liver_display.pvd");
  ASSERT_FALSE(files.empty());
  EXPECT_EQ(ReadVtu(out / files.back()).num_triangles(), 4384);
}

// A MixedSolid's series holds quadratic tets (VTK type 24): the vertices, then one node per
// edge where the P2 solution puts it, so ParaView draws the bent beam curved.
TEST(GipsiRun, MixedSolidWritesQuadraticTets) {
  fs::path out = TempDir("land_beam_p2");
  Result r = Gipsi("run -q " + Scene("land_beam_p2.json") + " --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  auto files = PvdFiles(out / "beam.pvd");
  ASSERT_EQ(files.size(), 2u);
  const Mesh beam = ReadVtu(out / files.back());
  ASSERT_EQ(beam.num_tets(), 480);  // 10 x 1 x 1 cubes of 6 tets, 2 per mm
  std::set<std::pair<int, int>> edges;
  for (Index e = 0; e < beam.num_tets(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) edges.insert(std::minmax(beam.tets(a, e), beam.tets(b, e)));
  ASSERT_EQ(beam.edge_nodes.cols(), Index(edges.size()));
  Index bent = 0;
  for (Index k = 0; k < beam.edge_nodes.cols(); ++k) {
    const Vec3 a = beam.nodes.col(beam.edge_node_ends(0, k));
    const Vec3 b = beam.nodes.col(beam.edge_node_ends(1, k));
    const double off = (beam.edge_nodes.col(k) - 0.5 * (a + b)).norm();
    EXPECT_LT(off, 0.1 * (b - a).norm()) << "edge " << k;  // a sane quadratic edge
    bent += off > 1e-9;
  }
  EXPECT_GT(bent, beam.edge_nodes.cols() / 2);
}

TEST(GipsiRun, ProfileShowsWhereTheTimeWent) {
  fs::path out = TempDir("cantilever");
  Result r =
      Gipsi("run -q --profile " + Scene("cantilever.json") + " --until 0.05 --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("profile (wall time):"));
  EXPECT_THAT(r.output, HasSubstr("object beam"));
  EXPECT_THAT(r.output, HasSubstr("assembly (residual, tangent)"));
  EXPECT_THAT(r.output, HasSubstr("linear solves"));
  EXPECT_THAT(r.output, HasSubstr("outputs (probes, VTU)"));
}

TEST(GipsiRun, RunsTheElectrophysiologySlabWithItsProfile) {
  fs::path out = TempDir("slab_ep");
  Result r = Gipsi("run -q --profile " + Scene("slab_ep_grid_0.5mm.json") +
                   " --until 0.004 --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("reaction (cell models)"));
  EXPECT_THAT(r.output, HasSubstr("diffusion (assembly and solves)"));
  EXPECT_TRUE(fs::exists(out / "probes" / "far_corner.csv"));
  EXPECT_TRUE(fs::exists(out / "tissue.pvd"));
}

TEST(GipsiRun, QuietPrintsOnlyWarningsAndErrors) {
  // The hanging sheet's corner is released at 1.5 s, an event the log reports at info level; a
  // resumed run reports where it resumed from, also at info level. -q prints neither: a run
  // without warnings prints nothing at all.
  const fs::path out = TempDir("quiet");
  const std::string run = "run " + Scene("hanging_sheet.json") + " --no-vtu -o " + out.string();
  Result loud = Gipsi(run + " --until 1.6");
  ASSERT_EQ(loud.code, 0) << loud.output;
  EXPECT_THAT(loud.output, HasSubstr("s: event: release the corner"));
  Result quiet = Gipsi(run + " --until 1.6 -q --checkpoint-every 1.0");
  ASSERT_EQ(quiet.code, 0) << quiet.output;
  EXPECT_EQ(quiet.output, "");
  const std::string resume = " --until 1.7 --resume " + (out / "checkpoint.gck").string();
  quiet = Gipsi(run + resume + " -q");
  ASSERT_EQ(quiet.code, 0) << quiet.output;
  EXPECT_EQ(quiet.output, "");
  loud = Gipsi(run + resume);
  ASSERT_EQ(loud.code, 0) << loud.output;
  EXPECT_THAT(loud.output, HasSubstr("resumed from"));
  EXPECT_THAT(loud.output, HasSubstr("s: event: release the corner"));
}

TEST(GipsiRun, DivergingSceneStopsWithDiagnosticAndKeepsOutputs) {
  fs::path dir = TempDir("diverge");
  {
    std::ofstream f(dir / "unstable.json");
    f << R"({"meshes": {"box": {"generate": "box", "min": [0,0,0], "max": [0.1,0.1,0.1],
                                "cells": [2,2,2]}},
      "objects": {"cube": {"type": "MassSpring", "domain": "box", "stiffness": 100000,
                           "integrator": "ExplicitEuler", "dt": 0.001}},
      "schedule": {"end": 10},
      "probes": {"ke": {"object": "cube", "fields": ["kinetic_energy"]}}})";
  }
  fs::path out = dir / "out";
  Result r = Gipsi("run " + (dir / "unstable.json").string() + " --out " + out.string());
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_THAT(r.output, HasSubstr("object 'cube' diverged at t = "));
  EXPECT_THAT(r.output, HasSubstr("outputs written up to t = "));
  // Everything written before the failure is intact and readable, with no NaN in it.
  auto files = PvdFiles(out / "cube.pvd");
  ASSERT_GE(files.size(), 2u);
  for (const auto& file : files) EXPECT_TRUE(ReadVtu(out / file).nodes.allFinite()) << file;
  std::ifstream csv(out / "probes" / "ke.csv");
  std::string line;
  std::getline(csv, line);
  std::size_t rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    EXPECT_EQ(line.find("nan"), std::string::npos) << line;
  }
  EXPECT_EQ(rows, files.size());
}

TEST(GipsiValidate, AcceptsTheDemoScenes) {
  for (const char* scene :
       {"hanging_sheet.json", "hanging_liver.json", "plugin_oscillator.json", "coupled_blocks.json",
        "cantilever.json", "indentation.json", "hanging_liver_fem.json", "slab_ep_0.5mm.json",
        "slab_ep_0.2mm.json", "slab_ep_grid_0.5mm.json", "slab_ep_grid_0.2mm.json",
        "spiral_wave.json", "lv_activation.json", "heart.json", "heart_mass_spring.json",
        "heart_fine.json", "heart_mixed.json"}) {
    Result r = Gipsi("validate " + Scene(scene));
    EXPECT_EQ(r.code, 0) << scene << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr("valid scene"));
  }
}

TEST(GipsiValidate, ListsEachConnectorsPortsAndOrderRules) {
  // The heart's connectors live inside its aggregate and are listed under its name; their
  // ports name the parts by their full names, as the command line takes them.
  const Result r = Gipsi("validate " + Scene("heart.json"));
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* line : {
           "connector heart.cavity_coupling CavityCoupling",
           "      reads heart.muscle.lumen_volume [m^3] (wall)",
           "      calls heart.blood as lumped chambers (blood)",
           "      writes heart.blood.lv_pressure_input [Pa] (blood)",
           "      fires after heart.muscle steps, before heart.blood steps, same time step, every "
           "macro step",
           "      reads heart.bioelectricity.V [mV] (from)",
       })
    EXPECT_THAT(r.output, HasSubstr(line));
}

TEST(GipsiValidate, SaysWhichStatesAStepRetrySerialises) {
  // Every part of the heart, its connectors and its monitor keep their state as a value.
  const Result heart = Gipsi("validate " + Scene("heart.json"));
  ASSERT_EQ(heart.code, 0) << heart.output;
  EXPECT_THAT(heart.output,
              HasSubstr("state: every object and connector keeps it as a value (a step retry "
                        "copies it)"));
  // So do the haptic probe and its coupling (a value gathered from the device, the tick and
  // the bridge's buffers).
  const Result palpation = Gipsi("validate " + Scene("liver_palpation.json"));
  ASSERT_EQ(palpation.code, 0) << palpation.output;
  EXPECT_THAT(palpation.output, HasSubstr("state: every object and connector keeps it as a value"));
}

TEST(GipsiRun, ResourceLimitsRefuseOversizedRunsBeforeWriting) {
  // hanging_sheet.json until 0.2 s writes 5 frames of the 441-node sheet (about 60 kB each).
  fs::path out = TempDir("limits");
  fs::remove_all(out);
  Result big = Gipsi("run " + Scene("hanging_sheet.json") +
                     " --until 0.2 --max-output 100kB --out " + out.string());
  EXPECT_EQ(big.code, 1) << big.output;
  EXPECT_THAT(big.output, HasSubstr("outputs.vtu.every: the run would write about"));
  EXPECT_THAT(big.output, HasSubstr("over the limit of 100 kB"));
  EXPECT_FALSE(fs::exists(out / "sheet.pvd"));
  Result cells =
      Gipsi("run " + Scene("hanging_sheet.json") + " --max-mesh-cells 100 --out " + out.string());
  EXPECT_EQ(cells.code, 1) << cells.output;
  EXPECT_THAT(cells.output, HasSubstr("over the limit of 100"));
  Result validate = Gipsi("validate " + Scene("hanging_sheet.json"));
  EXPECT_EQ(validate.code, 0) << validate.output;
  EXPECT_THAT(validate.output, HasSubstr("outputs: about"));
  Result bad = Gipsi("run " + Scene("hanging_sheet.json") + " --max-output lots");
  EXPECT_NE(bad.code, 0);
  EXPECT_THAT(bad.output, HasSubstr("--max-output"));
}

TEST(GipsiRun, CheckpointingASceneThatCannotSaveItsStateIsRefusedBeforeRunning) {
  // A synchronous probe moved by the viewer's mouse cannot be reproduced, so it keeps no
  // checkpointable state: the run must say so at once, before writing anything, not fail at its
  // first checkpoint. The scene is liver_palpation_mouse.json without "realtime" (a real-time
  // probe is refused earlier, for another reason), its meshes named by absolute paths.
  const fs::path dir = TempDir("no_checkpoints");
  nlohmann::json scene = nlohmann::json::parse(std::ifstream(Scene("liver_palpation_mouse.json")));
  ASSERT_EQ(scene["objects"]["probe"].erase("realtime"), 1u);
  for (auto& mesh : scene["meshes"]) mesh["file"] = Scene(mesh["file"].get<std::string>());
  std::ofstream(dir / "mouse.json") << scene.dump(2);
  const fs::path out = dir / "out";
  fs::remove_all(out);
  Result r = Gipsi("run " + (dir / "mouse.json").string() + " --checkpoint-every 0.1 --out " +
                   out.string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr("--checkpoint-every: this scene cannot be checkpointed: "
                                  "haptic probe 'probe' cannot be checkpointed or rolled back: "
                                  "its Mouse device is moved by the viewer's user"));
  EXPECT_FALSE(fs::exists(out));
}

TEST(GipsiValidate, BadInputsExitNonZeroWithAClearMessage) {
  fs::path dir = TempDir("bad");
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  };
  Result missing = Gipsi("validate " + (dir / "nope.json").string());
  EXPECT_EQ(missing.code, 1);
  EXPECT_THAT(missing.output, HasSubstr("nope.json: cannot open scene file for reading"));

  Result malformed = Gipsi("validate " + write("malformed.json", "{\"objects\": [1, 2,]}"));
  EXPECT_EQ(malformed.code, 1);
  EXPECT_THAT(malformed.output, HasSubstr("malformed.json: line 1, column 19: invalid JSON"));

  Result unknown =
      Gipsi("validate " +
            write("unknown.json",
                  R"({"objects": {"a": {"type": "Blob", "dt": 1}}, "schedule": {"end": 1}})"));
  EXPECT_EQ(unknown.code, 1);
  EXPECT_THAT(unknown.output, HasSubstr("objects.a.type: unknown object type 'Blob'"));

  Result broken =
      Gipsi("info " + std::string(GIPSI_SHARED_DATA_DIR) + "/liver/liver_for_test_broken.vtk");
  EXPECT_EQ(broken.code, 1);
  EXPECT_THAT(broken.output, HasSubstr("liver_for_test_broken.vtk: "));
}

TEST(GipsiInfo, DescribesTheLiverMesh) {
  Result r = Gipsi("info " + Scene("meshes/liver.msh"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("nodes:           181"));
  EXPECT_THAT(r.output, HasSubstr("tetrahedra:      596"));
  EXPECT_THAT(r.output, HasSubstr("closed and manifold"));
  EXPECT_THAT(r.output, HasSubstr("inverted tets:  0"));
}

TEST(GipsiHelp, EverySubcommandHasHelp) {
  for (const char* sub : {"", "run ", "validate ", "info ", "types "}) {
    Result r = Gipsi(std::string(sub) + "--help");
    EXPECT_EQ(r.code, 0) << sub;
    EXPECT_THAT(r.output, HasSubstr("Usage")) << sub;
  }
  EXPECT_NE(Gipsi("").code, 0);  // a subcommand is required
}

TEST(GipsiPlugins, TypesFromAPluginAreListedAndUsable) {
  std::string plugin = std::string(GIPSI_BINARY_DIR) + "/plugins/gipsi_example_plugin.so";
  Result types = Gipsi("types --plugin " + plugin);
  ASSERT_EQ(types.code, 0) << types.output;
  EXPECT_THAT(types.output, HasSubstr("Oscillator"));
  EXPECT_THAT(types.output, HasSubstr("Follow"));
  fs::path out = TempDir("plugin");
  Result run =
      Gipsi("run -q " + Scene("plugin_oscillator.json") + " --until 0.25 --out " + out.string());
  ASSERT_EQ(run.code, 0) << run.output;
  // The sheet edge follows the oscillator: at t = 0.25 s (a quarter period of 1 Hz) the driven
  // edge has moved by the amplitude, 0.02 m, up to the explicit integration error.
  std::ifstream csv(out / "probes" / "edge.csv");
  std::string line, last;
  while (std::getline(csv, line)) last = line;
  double t = 0, ux = 0, uy = 0, uz = 0;
  ASSERT_EQ(std::sscanf(last.c_str(), "%lf,%lf,%lf,%lf", &t, &ux, &uy, &uz), 4) << last;
  EXPECT_DOUBLE_EQ(t, 0.25);
  EXPECT_NEAR(uz, 0.02, 2e-4);
}

TEST(GipsiPlugins, APluginConnectorsPortsAreCheckedWhenTheSceneLoads) {
  // The example's Follow declares that it reads a velocity [m/s]; wired to the oscillator's
  // position [m], the scene is refused before anything runs, naming both ends.
  const fs::path dir = TempDir("plugin_ports");
  nlohmann::json scene = nlohmann::json::parse(std::ifstream(Scene("plugin_oscillator.json")));
  scene["connectors"]["shake"]["from"] = "driver.position";
  std::ofstream(dir / "wrong.json") << scene.dump(2);
  const std::string plugin = std::string(GIPSI_BINARY_DIR) + "/plugins/gipsi_example_plugin.so";
  const Result r = Gipsi("validate " + (dir / "wrong.json").string() + " --plugin " + plugin);
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr("wrong.json: connectors.shake: connector 'shake' (Follow) "
                                  "reads field 'position' of 'driver' (Oscillator) at its 'from' "
                                  "key, but the field is in [m], which does not convert to the "
                                  "connector's [m/s]"));
  const Result right = Gipsi("validate " + Scene("plugin_oscillator.json"));
  ASSERT_EQ(right.code, 0) << right.output;
  EXPECT_THAT(right.output, HasSubstr("reads driver.velocity [m/s] (from)"));
  EXPECT_THAT(right.output, HasSubstr("sets the boundary conditions of curtain (to)"));
}

TEST(GipsiPlugins, TwoPluginsRegisteringOneTypeNameAreRefusedNotAborted) {
  // The same plugin from two files (an installed one and a copy built elsewhere): the second
  // would register Oscillator and Follow again.
  const std::string plugin = std::string(GIPSI_BINARY_DIR) + "/plugins/gipsi_example_plugin.so";
  const fs::path copy = TempDir("plugin_twice") / "copy_of_example.so";
  fs::copy_file(plugin, copy);
  const Result r = Gipsi("types --plugin " + plugin + " --plugin " + copy.string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr(copy.string() +
                                  ": the plugin registers object type 'Oscillator', connector "
                                  "type 'Follow', already registered by GiPSi or an earlier "
                                  "plugin (the same plugin loaded from two files?)"));
}

TEST(GipsiPlugins, APluginOfAnotherReleaseLineOrInterfaceIsRefusedNamingBoth) {
  const std::string dir = std::string(GIPSI_BINARY_DIR) + "/tests/plugins/";
  const std::string here =
      fmt::format("this is gipsi {}.{} with plugin interface {}", GIPSI_VERSION_MAJOR,
                  GIPSI_VERSION_MINOR, GIPSI_PLUGIN_INTERFACE);
  Result next = Gipsi("types --plugin " + dir + "gipsi_test_next_minor_plugin.so");
  EXPECT_EQ(next.code, 1) << next.output;
  EXPECT_THAT(next.output,
              HasSubstr(fmt::format("plugin built for gipsi {}.{} with plugin interface {}, {}",
                                    GIPSI_VERSION_MAJOR, GIPSI_VERSION_MINOR + 1,
                                    GIPSI_PLUGIN_INTERFACE, here)));
  Result legacy = Gipsi("types --plugin " + dir + "gipsi_test_legacy_plugin.so");
  EXPECT_EQ(legacy.code, 1) << legacy.output;
  EXPECT_THAT(legacy.output,
              HasSubstr("plugin built for plugin interface 10 (an older gipsi), " + here));
}

TEST(GipsiPlugins, NotAPluginIsAClearError) {
  Result r = Gipsi("types --plugin " + std::string(GIPSI_BINARY_DIR) + "/bin/gipsi");
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.output, HasSubstr("cannot load plugin"));
}

}  // namespace
}  // namespace gipsi
