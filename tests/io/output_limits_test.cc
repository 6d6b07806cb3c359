// Resource limits for untrusted scenes: the output volume is estimated before a run (and a run
// over the limit is refused before anything is written), and scene meshes are capped in size.

#include <filesystem>
#include <fstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/outputs.h"
#include "gipsi/io/scene.h"
#include "gipsi/io/vtu_writer.h"
#include "temp_dir.h"

namespace gipsi {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

Scene Load(const std::string& text, const SceneLimits& limits = {}) {
  static TypeRegistry* registry = [] {
    auto* r = new TypeRegistry;
    RegisterBuiltins(*r);
    return r;
  }();
  return LoadSceneFromString(text, "scene.json", ".", *registry, limits);
}

/// A mass-spring block with a display-free VTU series every `every` and two probes.
std::string BlockScene(const std::string& vtu) {
  return R"({
  "meshes": {"box": {"generate": "box", "min": [0,0,0], "max": [0.1,0.1,0.1], "cells": [3,2,2]}},
  "objects": {
    "cube": {"type": "MassSpring", "domain": "box", "dt": 0.0001, "stiffness": 100,
             "boundary_conditions": [{"name": "top", "region": {"group": "zmax"}, "fix": true}]}
  },
  "schedule": {"end": 0.02, "dt": 0.001},
  "probes": {
    "corner": {"object": "cube", "point": [0, 0, 0], "fields": ["displacement"], "every": 0.002},
    "energy": {"object": "cube", "fields": ["kinetic_energy"]}
  },
  "outputs": {"vtu": )" +
         vtu + "}\n}";
}

std::uintmax_t BytesUnder(const fs::path& dir, const std::string& extension) {
  std::uintmax_t total = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.is_regular_file() && entry.path().extension() == extension)
      total += entry.file_size();
  return total;
}

std::size_t FilesUnder(const fs::path& dir, const std::string& extension) {
  std::size_t n = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    n += entry.is_regular_file() && entry.path().extension() == extension ? 1 : 0;
  return n;
}

TEST(VtuFileBytes, EqualsTheSizeOfTheWrittenFile) {
  // The estimate must be exact, not approximate: it decides whether a run may start. Cover
  // base64 padding (byte counts ≡ 0, 1, 2 mod 3), names needing XML escapes, multi-component
  // arrays, tets-only, triangles-only and field-free grids.
  const fs::path dir = testing::TestTempDir();
  for (Index n : {4, 5, 6, 17}) {
    Points nodes = Points::Random(3, n);
    Tets tets(4, n - 3);
    for (Index e = 0; e < tets.cols(); ++e) tets.col(e) << e, e + 1, e + 2, e + 3;
    Triangles triangles(3, n - 2);
    for (Index t = 0; t < triangles.cols(); ++t) triangles.col(t) << t, t + 1, t + 2;
    VtuFields fields;
    fields.point_data.push_back({"p<&>\"", 1, Eigen::MatrixXd::Random(1, n)});
    fields.point_data.push_back({"velocity", 3, Eigen::MatrixXd::Random(3, n)});
    fields.cell_data.push_back(
        {"stress", 9, Eigen::MatrixXd::Random(9, tets.cols() + triangles.cols())});
    std::vector<VtuArrayShape> point_shapes{{"p<&>\"", 1}, {"velocity", 3}},
        cell_shapes{{"stress", 9}};
    const fs::path mixed = dir / "mixed.vtu", tris = dir / "tris.vtu", bare = dir / "bare.vtu";
    WriteVtu(mixed, nodes, tets, triangles, fields);
    EXPECT_EQ(VtuFileBytes(n, tets.cols(), triangles.cols(), point_shapes, cell_shapes),
              fs::file_size(mixed))
        << n << " nodes";
    WriteVtu(tris, nodes, Tets(4, 0), triangles);
    EXPECT_EQ(VtuFileBytes(n, 0, triangles.cols(), {}, {}), fs::file_size(tris)) << n;
    WriteVtu(bare, nodes, tets, Triangles(3, 0));
    EXPECT_EQ(VtuFileBytes(n, tets.cols(), 0, {}, {}), fs::file_size(bare)) << n;
  }
}

TEST(EstimateOutputs, MatchesWhatARunWrites) {
  for (const std::string vtu : {R"({"every": 0.005})", "true"}) {
    Scene scene = Load(BlockScene(vtu));
    const OutputEstimate estimate = EstimateOutputs(scene);
    const fs::path out = testing::TestTempDir();
    AttachOutputs(scene, out);
    ASSERT_TRUE(scene.kernel->Run(scene.end_time).ok());
    // Frames: 0 to 20 ms every 5 ms (5), or every 1 ms macro step (21).
    EXPECT_EQ(estimate.vtu_frames, vtu == "true" ? 21 : 5);
    EXPECT_EQ(FilesUnder(out, ".vtu"), static_cast<std::size_t>(estimate.vtu_frames));
    // The frames' sizes are exact; the collection is estimated at 100 bytes a frame, which
    // bounds its real lines (about 70 bytes here) from above.
    const std::uintmax_t vtu_bytes = BytesUnder(out, ".vtu"), pvd_bytes = BytesUnder(out, ".pvd");
    EXPECT_EQ(estimate.vtu_bytes - 100 * static_cast<std::uintmax_t>(estimate.vtu_frames),
              vtu_bytes);
    EXPECT_LE(pvd_bytes, 100 * static_cast<std::uintmax_t>(estimate.vtu_frames) + 200);
    // Probe CSVs: an upper bound (every number counted at its widest), and not a loose one:
    // the corner probe writes 17-digit values, most of the numbers.
    const std::uintmax_t csv = BytesUnder(out, ".csv");
    EXPECT_LE(csv, estimate.probe_bytes);
    EXPECT_GE(csv, estimate.probe_bytes / 2);
    EXPECT_EQ(estimate.largest_series, "cube");
  }
}

TEST(OutputLimits, ARunOverTheLimitIsRefusedBeforeWritingAnything) {
  SceneLimits limits;
  limits.max_output_bytes = 50'000;  // a frame is about 12 kB: 21 frames do not fit, 3 do
  Scene scene = Load(BlockScene("true"), limits);
  const fs::path out = testing::TestTempDir() / "out";
  try {
    AttachOutputs(scene, out);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("scene.json"));
    EXPECT_THAT(e.what(), HasSubstr("outputs.vtu.every"));
    EXPECT_THAT(e.what(), HasSubstr("21 VTU frames"));
    EXPECT_THAT(e.what(), HasSubstr("over the limit of 50 kB"));
    EXPECT_THAT(e.what(), HasSubstr("--max-output"));
  }
  EXPECT_FALSE(fs::exists(out));
  // The same scene writing less often fits.
  Scene sparse = Load(BlockScene(R"({"every": 0.01})"), limits);
  EXPECT_LT(EstimateOutputs(sparse).total(), limits.max_output_bytes);
  EXPECT_NO_THROW(AttachOutputs(sparse, out));
}

TEST(OutputLimits, ProbesOverTheLimitNameTheProbes) {
  SceneLimits limits;
  limits.max_output_bytes = 2'000;
  Scene scene = Load(BlockScene("false"), limits);
  try {
    AttachOutputs(scene, testing::TestTempDir() / "out");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("probes"));
    EXPECT_THAT(e.what(), HasSubstr("probes.<name>.every"));
  }
}

TEST(MeshLimits, AMeshOverTheLimitIsRefusedNamingIt) {
  SceneLimits limits;
  limits.max_mesh_cells = 135;  // the 3x2x2 box: 36 nodes, 60 tets and 76 boundary triangles
  try {
    (void)Load(BlockScene("false"), limits);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("meshes.box"));
    EXPECT_THAT(e.what(), HasSubstr("36 nodes and 136 cells, over the limit of 135"));
    EXPECT_THAT(e.what(), HasSubstr("--max-mesh-cells"));
  }
  limits.max_mesh_cells = 136;
  EXPECT_NO_THROW((void)Load(BlockScene("false"), limits));
}

TEST(OutputPaths, AScenesOutputsStayInsideItsOutputDirectory) {
  // An untrusted scene must not pick where files go outside its folder of outputs.
  auto error = [](const std::string& outputs) {
    std::string text = BlockScene("false");
    text.replace(text.find(R"("outputs": {)"), 12, R"("outputs": {)" + outputs + ", ");
    try {
      (void)Load(text);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  for (const char* bad : {R"("directory": "/tmp/elsewhere")", R"("directory": "out/../../x")",
                          R"("directory": "..")", R"("directory": "")"})
    EXPECT_THAT(error(bad), HasSubstr("outputs.directory: expected a relative folder without '..'"))
        << bad;
  EXPECT_EQ(error(R"("directory": "out/run_1")"), "(no error)");
  for (const char* bad : {R"("plots": [{"file": "/tmp/x.png", "y": "energy.kinetic_energy"}])",
                          R"("plots": [{"file": "../x.png", "y": "energy.kinetic_energy"}])"})
    EXPECT_THAT(error(bad), HasSubstr("outputs.plots[0].file: expected a file name ending in .png "
                                      "or .svg (inside the output directory)"))
        << bad;
}

}  // namespace
}  // namespace gipsi
