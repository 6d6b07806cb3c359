// Scene input that used to be accepted silently, hang a run or garble its message (issue 22):
// duplicate keys, NaN literals, sampling intervals below the macro step, events after the end,
// files that are not regular files, messages that repeated themselves.

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/mesh_io.h"
#include "gipsi/io/sample_times.h"
#include "gipsi/io/scene.h"
#include "io/scene_test_util.h"
#include "temp_dir.h"

namespace gipsi {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

/// A valid scene with a 1 ms macro step; `object_extra` goes into the object, `top_extra` after
/// the schedule.
std::string SceneText(const std::string& object_extra = "", const std::string& top_extra = "",
                      const std::string& schedule_extra = "") {
  return R"({
  "meshes": {"box": {"generate": "box", "min": [0,0,0], "max": [0.1,0.1,0.1], "cells": [2,2,2]}},
  "objects": {
    "cube": {"type": "MassSpring", "domain": "box", "dt": 0.0001, "stiffness": 100)" +
         object_extra + R"(,
             "boundary_conditions": [{"name": "top", "region": {"group": "zmax"}, "fix": true}]}
  },
  "schedule": {"end": 0.01, "dt": 0.001)" +
         schedule_extra + "}" + top_extra + "\n}";
}

std::string LoadError(const std::string& text) { return testing::SceneLoadError(text); }

std::string LoadFileError(const fs::path& file) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  try {
    (void)LoadScene(file, registry);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

std::size_t Count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

TEST(SceneInput, DuplicateKeyIsRefusedWithItsPath) {
  EXPECT_EQ(LoadError(SceneText(", \"stiffness\": 200")),
            "scene.json: objects.cube: duplicate key 'stiffness' (JSON keys must be unique: one "
            "of the two would be ignored)");
  EXPECT_EQ(LoadError(SceneText("", "", ", \"end\": 1")),
            "scene.json: schedule: duplicate key 'end' (JSON keys must be unique: one of the two "
            "would be ignored)");
  EXPECT_EQ(LoadError(SceneText("", ", \"schedule\": {\"end\": 1}")),
            "scene.json: (document root): duplicate key 'schedule' (JSON keys must be unique: one "
            "of the two would be ignored)");
  // Inside an array the path names the item.
  EXPECT_THAT(LoadError(SceneText(", \"x\": [{\"a\": 1}, {\"b\": 1, \"b\": 2}]")),
              HasSubstr("scene.json: objects.cube.x[1]: duplicate key 'b'"));
}

TEST(SceneInput, NanLiteralGetsAReadableMessage) {
  const std::string error = LoadError(SceneText(", \"damping\": NaN"));
  EXPECT_THAT(error, HasSubstr("scene.json: line 4, column "));
  EXPECT_THAT(error, HasSubstr(": invalid JSON: syntax error while parsing value - invalid "
                               "literal; last read: '"));
  EXPECT_THAT(error, HasSubstr("(JSON has no NaN or infinity literals: give a finite number)"));
  EXPECT_THAT(LoadError(SceneText(", \"damping\": -Infinity")),
              HasSubstr("(JSON has no NaN or infinity literals: give a finite number)"));
  // Other syntax errors get no such hint.
  EXPECT_THAT(LoadError(SceneText(", \"damping\": tru")), Not(HasSubstr("NaN")));
}

TEST(SceneInput, MessagesSayWhatTheyGotOnce) {
  auto end = [](const std::string& value) {
    return LoadError(R"({"objects": {}, "schedule": {"end": )" + value + "}}");
  };
  EXPECT_EQ(end("-1"), "scene.json: schedule.end: expected a positive quantity, got -1 s");
  EXPECT_EQ(end("\"-1 ms\""),
            "scene.json: schedule.end: expected a positive quantity, got -0.001 s");
  EXPECT_EQ(end("\"fast\""),
            "scene.json: schedule.end: expected a number in s or a string \"VALUE UNIT\" (e.g. "
            "\"1.5 s\"), got \"fast\"");
}

TEST(SceneInput, AnErrorFromDeeperInTheSceneIsNotPrefixedTwice) {
  const std::string error = LoadError(R"({
    "objects": {"cube": {"type": "MassSpring", "domain": "nowhere", "dt": 0.001}},
    "schedule": {"end": 1}})");
  EXPECT_THAT(error, HasSubstr("scene.json: objects.cube.domain: no mesh named 'nowhere'"));
  EXPECT_EQ(Count(error, "scene.json"), 1u) << error;
}

TEST(SceneInput, SamplingIntervalsBelowTheMacroStepSampleEveryMacroStep) {
  // 1e-15 s used to mean 1e12 loop turns per 1 ms macro step (a hang); it is clamped to 0, every
  // macro step, with a warning (tests/apps/cli_exit_codes_test.cc checks its text).
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(SceneText("", R"(, "outputs": {"vtu": {"every": 1e-15}},
                   "probes": {"p": {"object": "cube", "fields": ["kinetic_energy"],
                                    "every": 1e-300},
                              "q": {"object": "cube", "fields": ["kinetic_energy"],
                                    "every": 0.002}})"),
                                    "scene.json", ".", registry);
  EXPECT_EQ(scene.vtu.every, 0.0);
  ASSERT_EQ(scene.probes.size(), 2u);
  EXPECT_EQ(scene.probes[0].every, 0.0);
  EXPECT_EQ(scene.probes[1].every, 0.002);  // at least the macro step: kept
}

TEST(SceneInput, EventAtOrAfterTheEndIsRefused) {
  const std::string event = R"(, "events": [{"at": 0.02, "object": "cube", "remove": "top"}])";
  EXPECT_EQ(LoadError(SceneText("", "", event)),
            "scene.json: schedule.events[0].at: the event at 0.02 s would never fire: the run "
            "ends at schedule.end = 0.01 s");
  EXPECT_EQ(LoadError(SceneText(
                "", "", R"(, "events": [{"at": 0.005, "object": "cube", "remove": "top"}])")),
            "(no error)");
}

TEST(SceneInput, NextSampleTimeIsBoundedForAnyInterval) {
  // A normal interval: one addition, bit for bit as before.
  EXPECT_EQ(NextSampleTime(0.05, 0.05, 0.05 + 1e-12), 0.05 + 0.05);
  // An interval so small that adding it changes nothing, and one that would take 1e12 steps:
  // both return at once with a time after t.
  const auto start = std::chrono::steady_clock::now();
  EXPECT_GT(NextSampleTime(0.5, 1e-300, 0.5), 0.5);
  EXPECT_GT(NextSampleTime(0.0, 1e-15, 1e-3), 1e-3);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
}

TEST(SceneInput, SceneFileMustBeARegularFileOfBoundedSize) {
  EXPECT_EQ(LoadFileError("/dev/zero"),
            "/dev/zero: is not a regular file (a device, pipe or socket), expected a scene file");
  const fs::path dir = gipsi::testing::TestTempDir();
  EXPECT_EQ(LoadFileError(dir), dir.string() + ": is a directory, expected a scene file");
  const fs::path big = dir / "big.json";
  std::ofstream(big).close();
  fs::resize_file(big, kMaxSceneFileBytes + 1);  // sparse: takes no disk space
  EXPECT_EQ(LoadFileError(big), big.string() +
                                    ": is 16777217 bytes, over the limit of 16777216 "
                                    "bytes for a scene file");
  EXPECT_THAT(LoadFileError(dir / "missing.json"),
              HasSubstr("missing.json: cannot open scene file for reading: No such file or "
                        "directory"));
}

TEST(SceneInput, MeshFileThatIsADirectoryOrDeviceNamesTheFileAndTheKey) {
  const fs::path dir = gipsi::testing::TestTempDir();
  fs::create_directories(dir / "liver.msh");
  const std::string scene = R"({"meshes": {"m": {"file": ")" + (dir / "liver.msh").string() +
                            R"("}}, "objects": {}, "schedule": {"end": 1}})";
  EXPECT_EQ(LoadError(scene), "scene.json: meshes.m.file: " + (dir / "liver.msh").string() +
                                  ": is a directory, expected a mesh file");
  fs::create_symlink("/dev/zero", dir / "zero.msh");
  EXPECT_EQ(LoadError(R"({"meshes": {"m": {"file": ")" + (dir / "zero.msh").string() +
                      R"("}}, "objects": {}, "schedule": {"end": 1}})"),
            "scene.json: meshes.m.file: " + (dir / "zero.msh").string() +
                ": is not a regular file (a device, pipe or socket), expected a mesh file");
}

TEST(SceneInput, MeshWithoutNodesIsRefused) {
  const fs::path dir = gipsi::testing::TestTempDir();
  std::ofstream(dir / "empty.obj").close();
  std::ofstream(dir / "gmsh.obj") << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
  for (const char* name : {"empty.obj", "gmsh.obj"}) {
    try {
      (void)ReadMesh(dir / name);
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), (dir / name).string() +
                                           ": the file holds no nodes: an empty mesh, or not a "
                                           ".obj file");
    }
  }
}

TEST(SceneInput, BuildProgressNamesEveryStage) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  std::vector<std::string> stages;
  (void)LoadSceneFromString(SceneText(), "scene.json", ".", registry, {},
                            [&](std::string_view stage, int done, int total) {
                              stages.push_back(fmt::format("{}/{} {}", done, total, stage));
                            });
  EXPECT_EQ(stages, (std::vector<std::string>{"0/5 mesh 'box' (generate box)",
                                              "1/5 object 'cube' (MassSpring)", "2/5 connectors",
                                              "3/5 events", "4/5 probes and outputs"}));
}

}  // namespace
}  // namespace gipsi
