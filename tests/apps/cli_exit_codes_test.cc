// The `gipsi` tool's exit-code contract (docs/cli.md), subcommand by subcommand: a bad command
// line exits 2, bad input 1, an output that cannot be written 4, a signal 130 — each with a
// message that names what is wrong. Also how `run` treats its output directory and a resume.

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "apps/cli_test_util.h"
#include "gipsi/base/version.h"
#include "gipsi/core/registry.h"
#include "gipsi/numerics/simd.h"
#include "test_paths.h"

extern char** environ;

namespace gipsi {
namespace {

namespace fs = std::filesystem;
using testing::Gipsi;
using testing::GipsiWithTinyFiles;
using ::testing::HasSubstr;
using ::testing::Not;
using testing::Result;

std::string Scene(const std::string& name) {
  return std::string(GIPSI_SOURCE_DIR) + "/scenes/" + name;
}

/// A regular file: a path under it cannot be created (ENOTDIR), even for root.
fs::path AFile(const fs::path& dir) {
  std::ofstream(dir / "a_file") << "not a directory\n";
  return dir / "a_file";
}

fs::path WriteCsv(const fs::path& dir) {
  std::ofstream(dir / "t.csv") << "time,a\n0,1\n1,2\n2,0\n";
  return dir / "t.csv";
}

TEST(GipsiExitCodes, VersionNamesThePackageAndPluginInterfaceVersionsAndTheOptionalParts) {
  const Result r = Gipsi("--version");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output, "gipsi " GIPSI_VERSION_STRING " (plugin interface " +
                          std::to_string(GIPSI_PLUGIN_INTERFACE) + "; with Gmsh, OpenIGTLink; " +
                          SimdKernelsName(ActiveSimdKernels()) + " kernels)\n");
}

TEST(GipsiExitCodes, BadCommandLineExits2ForEverySubcommand) {
  const std::string sheet = Scene("hanging_sheet.json");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "A subcommand is required"},
      {"run " + sheet + " --bogus", "not expected: --bogus"},
      {"run " + sheet + " --until -1", "--until: expected a positive number of seconds, got '-1'"},
      {"run " + sheet + " --until 0", "--until: expected a positive number of seconds, got '0'"},
      {"run " + sheet + " --until nan",
       "--until: expected a positive number of seconds, got 'nan'"},
      {"run " + sheet + " --until 1e999",
       "--until: expected a positive number of seconds, got '1e999'"},
      {"run " + sheet + " --checkpoint-every inf",
       "--checkpoint-every: expected a positive number of seconds, got 'inf'"},
      {"validate", "SCENE is required"},
      {"validate " + sheet + " --max-mesh-cells 0",
       "--max-mesh-cells: expected a positive whole number, got '0'"},
      {"info", "MESH is required"},
      {"types --bogus", "not expected: --bogus"},
      {"cell AlievPanfilov --beats 0",
       "--beats: expected a whole number of beats from 1 to 1000000, got '0'"},
      {"cell AlievPanfilov --apd 200", "--apd: expected a percentage in (0, 100], got '200'"},
      {"snapshot " + sheet, "--out is required"},
      {"snapshot " + sheet + " --out x.png --time -1",
       "--time: expected a non-negative number of seconds, got '-1'"},
      {"view " + sheet + " --speed nan",
       "--speed: expected a non-negative real-time factor, got 'nan'"},
      {"plot", "CSV is required"},
  };
  for (const auto& [args, message] : cases) {
    const Result r = Gipsi(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr("gipsi: error: command line: ")) << args;
    EXPECT_THAT(r.output, HasSubstr(message)) << args;
    // CLI11's own range messages printed DBL_MAX in 309 digits, or "0.000000".
    EXPECT_THAT(r.output, Not(HasSubstr("1797693134862315"))) << args;
    EXPECT_THAT(r.output, Not(HasSubstr("0.000000"))) << args;
  }
}

// A launcher's environment with several ranks: a build without PETSc refuses the run (each
// rank would run the whole scene and write the same files); a build with it starts MPI, which
// without a real launcher behind the variables is a world of one rank, a serial run. Real
// distributed runs are tested by Mpi.SceneRunMatchesTheSerialRun (tests/parallel/).
TEST(GipsiExitCodes, RunOnSeveralMpiRanksIsRefusedWithoutPetsc) {
  const std::string sheet = Scene("hanging_sheet.json");
  const fs::path dir = testing::TestTempDir();
  for (const char* launcher : {"OMPI_COMM_WORLD_SIZE=2", "PMI_SIZE=4", "SLURM_STEP_NUM_TASKS=8"}) {
    const Result r = Gipsi(
        "run " + sheet + " --until 0.01 --no-vtu -o " + (dir / "out").string() + " --overwrite",
        std::string("export ") + launcher + ";");
#if GIPSI_TEST_WITH_PETSC
    if (std::string(launcher).rfind("OMPI", 0) != 0) continue;  // Open MPI's own variable only
    EXPECT_EQ(r.code, 0) << launcher << "\n" << r.output;
    EXPECT_THAT(r.output, Not(HasSubstr("MPI ranks:"))) << launcher;
#else
    EXPECT_EQ(r.code, 2) << launcher << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr("started on several MPI ranks")) << launcher;
    EXPECT_THAT(r.output, HasSubstr("docs/scale-out.md")) << launcher;
#endif
  }
  // One rank is a serial run.
  const Result one =
      Gipsi("run " + sheet + " --until 0.01 --no-vtu -q --overwrite -o " + (dir / "out").string(),
            "export OMPI_COMM_WORLD_SIZE=1;");
  EXPECT_EQ(one.code, 0) << one.output;
}

TEST(GipsiExitCodes, BadInputExits1ForEverySubcommand) {
  const fs::path dir = testing::TestTempDir();
  const std::string sheet = Scene("hanging_sheet.json");
  const std::string missing = (dir / "missing.json").string();
  fs::create_directories(dir / "m.msh");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"run " + missing, "missing.json: cannot open scene file for reading"},
      {"validate /dev/zero",
       "/dev/zero: is not a regular file (a device, pipe or socket), expected a scene file"},
      {"validate " + dir.string(), ": is a directory, expected a scene file"},
      {"info " + (dir / "m.msh").string(), "m.msh: is a directory, expected a mesh file"},
      {"types --plugin " + missing, "missing.json: plugin file not found"},
      {"cell LuoRudy", "command line: cell.model: unknown cell model 'LuoRudy'"},
      {"snapshot " + missing + " --out " + (dir / "x.png").string(),
       "missing.json: cannot open scene file for reading"},
      {"view " + sheet + " --size 1x1",
       "command line: --size: expected whole numbers of pixels in [200, 8192], got '1x1'"},
      {"plot " + missing + " --out " + (dir / "x.png").string(), "missing.json"},
  };
  for (const auto& [args, message] : cases) {
    const Result r = Gipsi(args);
    EXPECT_EQ(r.code, 1) << args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr("gipsi: error: ")) << args;
    EXPECT_THAT(r.output, HasSubstr(message)) << args << "\n" << r.output;
  }
}

TEST(GipsiExitCodes, UnwritableOutputExits4ForEveryCommandThatWrites) {
  // `view` writes only --screenshot images, which need a display: tests/viz covers it.
  const fs::path dir = testing::TestTempDir();
  const fs::path file = AFile(dir);
  const std::string sheet = Scene("hanging_sheet.json");
  const std::string csv = WriteCsv(dir).string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"run " + sheet + " --until 0.01 --out " + (file / "out").string(),
       (file / "out").string() + ": cannot create directories: Not a directory"},
      {"snapshot " + sheet + " --size 64x48 --out " + (file / "x.png").string(),
       (file / "x.png").string() + ": cannot create the file: Not a directory"},
      {"plot " + csv + " --out " + (file / "x.png").string(),
       (file / "x.png").string() + ": cannot create the file: Not a directory"},
      {"cell AlievPanfilov --dt 0.05 --out " + (file / "x.csv").string(),
       (file / "x.csv").string() + ": cannot create the file: Not a directory"},
  };
  for (const auto& [args, message] : cases) {
    const Result r = Gipsi(args);
    EXPECT_EQ(r.code, 4) << args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr("gipsi: error: ")) << args;
    EXPECT_THAT(r.output, HasSubstr(message)) << args << "\n" << r.output;
  }
}

TEST(GipsiExitCodes, AFullDiskExits4WithTheReasonAndLeavesNoPartialFile) {
  // Every file limited to 512 bytes: the first VTU frame, a PNG and a plot do not fit.
  const fs::path dir = testing::TestTempDir();
  const std::string sheet = Scene("hanging_sheet.json");

  const Result run =
      GipsiWithTinyFiles("run " + sheet + " --until 0.01 --out " + (dir / "run").string());
  EXPECT_EQ(run.code, 4) << run.output;
  const fs::path frame = dir / "run" / "sheet" / "sheet_000000.vtu";
  EXPECT_THAT(run.output, HasSubstr(frame.string() + ": cannot write: File too large"));
  EXPECT_FALSE(fs::exists(frame));
  EXPECT_FALSE(fs::exists(frame.string() + ".tmp"));

  const fs::path png = dir / "snapshot.png";
  const Result snapshot = GipsiWithTinyFiles("snapshot " + sheet + " --out " + png.string());
  EXPECT_EQ(snapshot.code, 4) << snapshot.output;
  EXPECT_THAT(snapshot.output, HasSubstr(png.string() + ": cannot write: File too large"));
  EXPECT_FALSE(fs::exists(png));

  const fs::path plot = dir / "plot.png";
  const Result plotted =
      GipsiWithTinyFiles("plot " + WriteCsv(dir).string() + " --out " + plot.string());
  EXPECT_EQ(plotted.code, 4) << plotted.output;
  EXPECT_THAT(plotted.output, HasSubstr(plot.string() + ": cannot write: "));
  EXPECT_FALSE(fs::exists(plot));
}

/// Starts `gipsi ARGS` with its output in `log`; returns its process id.
pid_t Spawn(const std::vector<std::string>& args, const fs::path& log) {
  const std::string binary = std::string(GIPSI_BINARY_DIR) + "/bin/gipsi";
  std::string command = "exec " + binary;
  for (const auto& a : args) command += " " + a;
  command += " >" + log.string() + " 2>&1";
  std::vector<char*> argv = {const_cast<char*>("/bin/sh"), const_cast<char*>("-c"), command.data(),
                             nullptr};
  pid_t pid = -1;
  EXPECT_EQ(posix_spawn(&pid, "/bin/sh", nullptr, nullptr, argv.data(), environ), 0);
  return pid;
}

/// Waits up to `limit` for `pid`; its exit code (-1 if it had to be killed) and the seconds
/// it took.
std::pair<int, double> WaitFor(pid_t pid, std::chrono::seconds limit) {
  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() - start > limit) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return {-1, 0};
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, seconds};
}

std::string ReadAll(const fs::path& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(GipsiSignals, SigtermStopsARunningRunWithinAMacroStep) {
  const fs::path dir = testing::TestTempDir();
  const pid_t pid = Spawn({"run", Scene("hanging_sheet.json"), "--until", "10000", "--no-vtu", "-q",
                           "--out", (dir / "out").string()},
                          dir / "log");
  // Wait until it runs: its probe CSV has rows (however loaded the machine is).
  const fs::path csv = dir / "out" / "probes" / "centre.csv";
  for (int i = 0; i < 600 && ReadAll(csv).size() < 1000; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  kill(pid, SIGTERM);
  const auto [code, seconds] = WaitFor(pid, std::chrono::seconds(20));
  EXPECT_EQ(code, 130) << ReadAll(dir / "log");
  EXPECT_LT(seconds, 2.0);  // measured 0.06 s: a macro step takes well under a millisecond
  EXPECT_THAT(ReadAll(dir / "log"), HasSubstr("stopped on request at t = "));
}

TEST(GipsiSignals, SigintStopsALongBuildThatReportsItsStages) {
  // A box of a million cells takes tens of seconds to build.
  const fs::path dir = testing::TestTempDir();
  std::ofstream(dir / "big.json") << R"({
    "meshes": {"box": {"generate": "box", "min": [0,0,0], "max": [1,1,1], "cells": [100,100,100]}},
    "objects": {"cube": {"type": "MassSpring", "domain": "box", "dt": 0.001}},
    "schedule": {"end": 1}})";
  const pid_t pid = Spawn({"validate", (dir / "big.json").string()}, dir / "log");
  // Not a terminal: once the mesh stage has taken 2 s, a plain line says so. Wait for it (the
  // build takes tens of seconds), so the signal surely comes while building, however loaded the
  // machine is.
  const std::string stage = "building: [1/5] mesh 'box' (generate box) ...\n";
  for (int i = 0; i < 600 && ReadAll(dir / "log").find(stage) == std::string::npos; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_THAT(ReadAll(dir / "log"), HasSubstr(stage));
  kill(pid, SIGINT);
  const auto [code, seconds] = WaitFor(pid, std::chrono::seconds(60));
  EXPECT_EQ(code, 130) << ReadAll(dir / "log");
  EXPECT_LT(seconds, 2.0);  // measured 0.2 s: at once, not at the end of the build
  EXPECT_THAT(ReadAll(dir / "log"),
              HasSubstr("gipsi: stopped on request while building the scene"));
}

TEST(GipsiRunOutputs, ASamplingIntervalBelowTheMacroStepSamplesEveryStepInsteadOfHanging) {
  const fs::path dir = testing::TestTempDir();
  std::ofstream(dir / "tiny.json") << R"({
    "meshes": {"box": {"generate": "box", "min": [0,0,0], "max": [0.1,0.1,0.1], "cells": [2,2,2]}},
    "objects": {"cube": {"type": "MassSpring", "domain": "box", "dt": 0.001}},
    "schedule": {"end": 0.005},
    "probes": {"ke": {"object": "cube", "fields": ["kinetic_energy"], "every": 1e-300}},
    "outputs": {"vtu": {"every": 1e-15}}})";
  const std::string warning =
      "outputs.vtu.every: a sampling interval of 1e-15 s is shorter than the macro step of "
      "0.001 s (schedule.dt, or the largest object dt): sampling every macro step instead";
  const Result validate = Gipsi("validate " + (dir / "tiny.json").string());
  EXPECT_EQ(validate.code, 0) << validate.output;
  EXPECT_THAT(validate.output, HasSubstr(warning));
  EXPECT_THAT(validate.output, HasSubstr("probes.ke.every: a sampling interval of 1e-300 s"));
  const Result run =
      Gipsi("run " + (dir / "tiny.json").string() + " --out " + (dir / "out").string());
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_TRUE(fs::exists(dir / "out" / "cube" / "cube_000005.vtu"));  // t = 0 ... 5 ms
  EXPECT_FALSE(fs::exists(dir / "out" / "cube" / "cube_000006.vtu"));
}

TEST(GipsiRunOutputs, ARerunIntoTheSameFolderIsRefusedUnlessOverwrite) {
  const fs::path out = testing::TestTempDir() / "out";
  const std::string run = "run -q " + Scene("hanging_sheet.json") + " --out " + out.string();
  ASSERT_EQ(Gipsi(run + " --until 0.2").code, 0);
  std::ofstream(out / "notes.txt") << "mine\n";
  std::ofstream(out / "sheet" / "notes.txt") << "mine too\n";

  const Result refused = Gipsi(run + " --until 0.1");
  EXPECT_EQ(refused.code, 1) << refused.output;
  EXPECT_THAT(refused.output,
              HasSubstr("command line: --out: " + out.string() +
                        " holds VTU series of an earlier run (e.g. sheet (6 files)); a new run "
                        "would leave frames its .pvd does not list: choose another --out, or "
                        "add --overwrite to delete the earlier series there first"));
  EXPECT_TRUE(fs::exists(out / "sheet" / "sheet_000004.vtu"));  // nothing deleted

  const Result overwritten = Gipsi(run + " --until 0.1 --overwrite");
  ASSERT_EQ(overwritten.code, 0) << overwritten.output;
  std::vector<std::string> frames;
  for (const auto& entry : fs::directory_iterator(out / "sheet"))
    frames.push_back(entry.path().filename().string());
  std::sort(frames.begin(), frames.end());
  EXPECT_EQ(frames, (std::vector<std::string>{"notes.txt", "sheet_000000.vtu", "sheet_000001.vtu",
                                              "sheet_000002.vtu"}));
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
}

TEST(GipsiRunOutputs, AResumedRunCountsItsOwnStepsAndMustEndAfterTheCheckpoint) {
  const fs::path out = testing::TestTempDir() / "out";
  const std::string run = "run " + Scene("hanging_sheet.json") + " --no-vtu --out " + out.string();
  ASSERT_EQ(Gipsi(run + " -q --until 1.0 --checkpoint-every 0.5").code, 0);
  const std::string resume = run + " --resume " + (out / "checkpoint.gck").string();
  const Result resumed = Gipsi(resume + " --until 1.2");
  ASSERT_EQ(resumed.code, 0) << resumed.output;
  EXPECT_THAT(resumed.output, HasSubstr("simulated time:   0.2 s (from 1 s)"));
  EXPECT_THAT(resumed.output, HasSubstr("macro steps:      200 of 0.001 s"));
  EXPECT_THAT(resumed.output,
              HasSubstr("sheet                MassSpring     1000 steps of 0.0002 s"));

  const Result early = Gipsi(resume + " --until 0.8");
  EXPECT_EQ(early.code, 1) << early.output;
  EXPECT_THAT(
      early.output,
      HasSubstr("command line: --until: the checkpoint " + (out / "checkpoint.gck").string() +
                " is at t = 1 s, not before the end of the run at 0.8 s (--until): "
                "nothing to run (give a later --until)"));
}

TEST(GipsiInfo, NamesTetsByTheFilesOwnIds) {
  // Gmsh element tags 7 and 9; tag 9 is inverted. `info` used to call it "1" (its 0-based index).
  const fs::path dir = testing::TestTempDir();
  std::ofstream(dir / "two.msh") << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n"
                                    "1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0 0 -1\n$EndNodes\n"
                                    "$Elements\n2\n7 4 2 0 1 1 2 3 4\n9 4 2 0 1 1 2 3 5\n"
                                    "$EndElements\n";
  const Result r = Gipsi("info " + (dir / "two.msh").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("inverted tets:  1 — ids: 9 (Gmsh element tags)"));
  // A MassSpring accepted such a mesh silently; it warns now.
  std::ofstream(dir / "two.json") << R"({"meshes": {"two": {"file": "two.msh"}},
    "objects": {"tets": {"type": "MassSpring", "domain": "two", "dt": 0.001}},
    "schedule": {"end": 1}})";
  const Result validate = Gipsi("validate " + (dir / "two.json").string());
  EXPECT_EQ(validate.code, 0) << validate.output;
  EXPECT_THAT(validate.output,
              HasSubstr("two.json: objects.tets: 1 of 2 tets of the domain are inverted "
                        "(negative volume in node order 0-1-2-3; the first is tet 9 (Gmsh "
                        "element tag)): volume preservation would push them further inside "
                        "out; fix the mesh's node order (`gipsi info` lists them)"));
  // A FemSolid refuses it, naming the tet as the file does (it used to say "elements 1").
  std::ofstream(dir / "fem.json") << R"({"meshes": {"two": {"file": "two.msh"}},
    "objects": {"tets": {"type": "FemSolid", "domain": "two", "dt": 0.001,
      "material": {"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.3}}},
    "schedule": {"end": 1}})";
  const Result fem = Gipsi("validate " + (dir / "fem.json").string());
  EXPECT_NE(fem.code, 0) << fem.output;
  EXPECT_THAT(fem.output, HasSubstr("1 tetrahedra are inverted or degenerate (non-positive rest "
                                    "volume), e.g. tets 9 (Gmsh element tags)"));
  // A format without ids of its own says which ids it prints.
  std::ofstream(dir / "two.vtk")
      << "# vtk DataFile Version 3.0\ntwo\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 double\n"
         "0 0 0\n1 0 0\n0 1 0\n0 0 1\n0 0 -1\nCELLS 2 10\n4 0 1 2 3\n4 0 1 2 4\n"
         "CELL_TYPES 2\n10\n10\n";
  const Result vtk = Gipsi("info " + (dir / "two.vtk").string());
  ASSERT_EQ(vtk.code, 0) << vtk.output;
  EXPECT_THAT(vtk.output, HasSubstr("inverted tets:  1 — ids: 1 (0-based indices in file order)"));
}

}  // namespace
}  // namespace gipsi
