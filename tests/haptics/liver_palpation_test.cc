// The shipped haptic palpation scene: it loads, and a shortened run (settling, the first press
// and its hold) presses into the liver at 1 kHz with the organ in equilibrium with its support.

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/haptics/haptic_probe.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/fem/fem_solid.h"
#include "test_paths.h"

namespace gipsi {
namespace {

TEST(LiverPalpationScene, PressesIntoTheLiverAndTheSupportCarriesToolAndWeight) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadScene(std::string(GIPSI_SOURCE_DIR) + "/scenes/liver_palpation.json", registry);
  EXPECT_EQ(scene.plots.size(), 2u);
  // Shortened run: settle 0.5 s, press until 1.5 s, hold until 2.5 s (the full scene then
  // lifts the probe and presses a second point until 5 s).
  const RunResult run = scene.kernel->Run(2.5);
  ASSERT_TRUE(run.ok()) << run.diagnostic;
  auto& liver = dynamic_cast<FemSolid&>(scene.kernel->FindObject("liver"));
  auto& probe = dynamic_cast<HapticProbe&>(scene.kernel->FindObject("probe"));
  EXPECT_EQ(probe.num_ticks(), 2500);  // 1 kHz
  Eigen::MatrixXd model_force(1, 1);
  probe.ReadField(probe.FindField("model_force"), model_force);
  // Loads on the liver: gravity, the tool (a boundary force on the contact vertex) and the
  // support's reactions.
  const BoundarySurface& bnd = liver.boundary();
  Vec3 tool = Vec3::Zero();
  for (Index j = 0; j < bnd.num_vertices(); ++j) tool += liver.boundary_conditions().force(j);
  Points reaction(3, bnd.num_vertices());
  liver.ReadField(liver.FindField("reaction_force"), reaction);
  const Vec3 support = reaction.rowwise().sum();
  const double weight = liver.params().density * liver.assembly().volumes().sum() * 9.81;
  std::printf("tool force on the liver %.4f N (model %.4f N), support %.4f N, weight %.4f N\n",
              tool.norm(), model_force(0, 0), support.z(), weight);
  EXPECT_GT(model_force(0, 0), 0.02);  // the probe is pressing (a few mm into soft tissue)
  EXPECT_NEAR(tool.norm(), model_force(0, 0), 0.05 * model_force(0, 0));
  // After 1 s of hold with mass-proportional damping 1/s the organ is close to static
  // equilibrium: support + tool + weight = the rate of momentum (small); 2 % of the weight.
  EXPECT_LT((support + tool + Vec3(0, 0, -weight)).norm(), 0.02 * weight);
}

TEST(LiverPalpationScene, BadHapticKeysAreErrorsNamingTheJsonPath) {
  std::ifstream in(std::string(GIPSI_SOURCE_DIR) + "/scenes/liver_palpation.json");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string scene = buffer.str();
  auto error = [&](const std::string& from, const std::string& to) -> std::string {
    std::string text = scene;
    const auto at = text.find(from);
    if (at == std::string::npos) return "(pattern not in the scene)";
    text.replace(at, from.size(), to);
    TypeRegistry registry;
    RegisterBuiltins(registry);
    try {
      (void)LoadSceneFromString(text, "palpation.json", std::string(GIPSI_SOURCE_DIR) + "/scenes",
                                registry);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  };
  using ::testing::HasSubstr;
  EXPECT_THAT(error(R"("device": "probe")", R"("device": "liver")"),
              HasSubstr("connectors.haptics.device: object 'liver' (FemSolid) is not a haptic "
                        "device; a device is a HapticProbe (or a plugin type implementing "
                        "HapticEndpoint)"));
  EXPECT_THAT(error(R"("rate": 1000,)", R"("rate": 1000, "ratee": 3,)"),
              HasSubstr("objects.probe: unknown key 'ratee' (did you mean 'rate'?)"));
  EXPECT_THAT(error("[1.5, -0.0175", "[0.4, -0.0175"),
              HasSubstr("objects.probe.path[2]: keyframe times must increase strictly"));
  EXPECT_THAT(error(R"("rate": 1000,)", R"("rate": 20000,)"),
              HasSubstr("objects.probe.rate: expected a rate in (0, 10000] Hz"));
  EXPECT_THAT(error(R"("capture_distance": 0.01)", R"("capture_distance": -1)"),
              HasSubstr("connectors.haptics.capture_distance"));
}

}  // namespace
}  // namespace gipsi
