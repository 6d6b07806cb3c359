// The vector kernels change the speed of a run, never its results: whole scenes write the same
// bytes with the AVX kernels and with the generic ones (GIPSI_SIMD=generic), for the three laws
// with batch kernels and the fused Jacobi-CG. On a processor without AVX both runs use the
// generic kernels and the comparison holds trivially; the --version check says which ran.

#include <filesystem>
#include <map>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "apps/cli_test_util.h"
#include "gipsi/numerics/simd.h"
#include "io/io_test_util.h"

namespace gipsi {
namespace {

namespace fs = std::filesystem;

/// Every file under `dir`: relative path → bytes.
std::map<std::string, std::string> Tree(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.is_regular_file())
      files[fs::relative(entry.path(), dir).string()] = test::ReadBytes(entry.path());
  return files;
}

TEST(SimdKernels, GenericKernelsAreSelectedByTheEnvironment) {
  const testing::Result r = testing::Gipsi("--version", "GIPSI_SIMD=generic");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, ::testing::HasSubstr("; generic kernels)"));
}

// The cantilever (corotational, Newton with the default, fused Jacobi-CG), the hanging liver
// (neo-Hookean, lagged CHOLMOD) for its first step and the heart's first 0.1 s (Guccione with
// the active tension rising): frames, probes, series and plots byte for byte.
TEST(SimdKernels, ScenesWriteTheSameBytesWithAvxAndGenericKernels) {
  const fs::path dir = testing::TestTempDir();
  const std::string scenes = std::string(GIPSI_SOURCE_DIR) + "/scenes/";
  for (const auto& [scene, until] : {std::pair<std::string, std::string>{"cantilever.json", ""},
                                     {"hanging_liver_fem.json", " --until 0.01"},
                                     {"heart.json", " --until 0.1"}}) {
    const fs::path active = dir / (scene + ".active"), generic = dir / (scene + ".generic");
    const testing::Result a =
        testing::Gipsi("run " + scenes + scene + until + " -q --out " + active.string());
    ASSERT_EQ(a.code, 0) << a.output;
    const testing::Result g = testing::Gipsi(
        "run " + scenes + scene + until + " -q --out " + generic.string(), "GIPSI_SIMD=generic");
    ASSERT_EQ(g.code, 0) << g.output;
    const auto active_files = Tree(active), generic_files = Tree(generic);
    ASSERT_GE(active_files.size(), 2u) << scene;
    EXPECT_TRUE(active_files == generic_files)
        << scene << ": the outputs differ between the " << SimdKernelsName(ActiveSimdKernels())
        << " and the generic kernels";
  }
}

}  // namespace
}  // namespace gipsi
