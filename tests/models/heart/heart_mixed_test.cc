// The Heart with "muscle_model": "mixed" (scenes/heart_mixed.json): an incompressible muscle on
// Taylor–Hood P2–P1 elements whose curved cavity is coupled to the blood.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/circulation/circulation.h"
#include "gipsi/models/fem/mixed_solid.h"
#include "gipsi/models/heart/heart.h"
#include "test_paths.h"

namespace gipsi {
namespace {

/// The heart on a coarse ventricle with the mixed muscle.
const char* kScene = R"({"gipsi": 1, "units": "SI",
  "meshes": {"lv": {"generate": "ellipsoid_shell", "endo": [0.022, 0.048],
                    "epi": [0.032, 0.058], "base_z": 0.012, "size": 0.012}},
  "objects": {"heart": {"type": "Heart", "muscle_model": "mixed", "dt": "5 ms"}},
  "schedule": {"end": "50 ms"}})";

// 50 ms of the first beat's filling: after every step the wall's curved cavity encloses the
// blood's volume compressed by p/K (K = 20 MPa, the heart's) to Newton's tolerance (1e-6 of the
// residual, which weighs the volume mismatch by the blood's stiffness: measured 5.4e-9 of the
// volume), and the incompressible wall keeps its volume. The P2–P1 constraint is ∫ ln J L_b = 0
// for the linear pressure shapes L_b, so ∫ ln J dV = 0 exactly and ∫ J dV grows by about
// ∫ (ln J)²/2: 1.1e-3 at 50 ms on this mesh, one or two tets through the wall (the penalty
// tets of the FEM heart lose 3 % of theirs in the first 80 ms, 11 % by end-systole: docs/heart.md).
TEST(HeartMixed, StepsWithTheIncompressibleWallEnclosingTheBlood) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(kScene, "scene.json", ".", registry);
  auto& heart = dynamic_cast<Heart&>(scene.kernel->FindObject("heart"));
  auto& muscle = dynamic_cast<MixedSolid&>(*heart.FindPart("muscle"));
  auto& blood = dynamic_cast<Circulation&>(*heart.FindPart("blood"));
  EXPECT_TRUE(muscle.params().incompressible);
  EXPECT_TRUE(muscle.dynamic());
  const int lv = blood.FindCompartment("lv");
  const double wall = muscle.CurrentVolume();
  double worst_cavity = 0, worst_wall = 0;
  for (int i = 1; i <= 10; ++i) {
    const RunResult result = scene.kernel->Run(5e-3 * i);
    ASSERT_TRUE(result.ok()) << result.diagnostic;
    const double p = blood.pressure(lv);
    const double v = blood.volume(lv);
    worst_cavity =
        std::max(worst_cavity, std::abs(muscle.CavityVolume(0) - v * (1 - p / 20e6)) / v);
    worst_wall = std::max(worst_wall, std::abs(muscle.CurrentVolume() / wall - 1));
    EXPECT_EQ(muscle.CavityPressure(0), p);  // the blood integrates with the wall's pressure
  }
  EXPECT_LT(worst_cavity, 2e-8);
  EXPECT_LT(worst_wall, 2e-3);
  EXPECT_GT(blood.volume(lv), 70e-6);  // it filled from the atrium
}

// The first beat of scenes/heart_mixed.json (the demo's mesh): the incompressible wall fills,
// contracts and ejects, and its volume stays within 0.5 % (measured
// 0.26 %, at end-systole; the FEM heart's penalty tets lose 11 %). Beat 1 measured: EDV 123.7 mL,
// ESV 30.5 mL, EF 75 %, LV peak 131 mmHg, aorta 118/78 mmHg (beat 5: EF 54 %, docs/heart.md).
TEST(HeartMixed, FirstBeatEjectsWithTheWallKeepingItsVolume) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP()
      << "a coupled beat on P2 elements takes minutes under ASan; the release build runs it";
#endif
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadScene(std::string(GIPSI_SOURCE_DIR) + "/scenes/heart_mixed.json", registry);
  auto& heart = dynamic_cast<Heart&>(scene.kernel->FindObject("heart"));
  auto& muscle = dynamic_cast<MixedSolid&>(*heart.FindPart("muscle"));
  std::printf("[ info     ] the muscle: %ld P2 tets, %ld unknowns\n",
              static_cast<long>(muscle.quadratic_mesh().num_elements()),
              static_cast<long>(muscle.num_unknowns()));
  const double wall = muscle.CurrentVolume();
  double worst_wall = 0;
  for (int i = 1; i <= 160; ++i) {
    const RunResult result = scene.kernel->Run(5e-3 * i);
    ASSERT_TRUE(result.ok()) << result.diagnostic;
    worst_wall = std::max(worst_wall, std::abs(muscle.CurrentVolume() / wall - 1));
  }
  EXPECT_LT(worst_wall, 5e-3);
  ASSERT_EQ(heart.beats().size(), 1U);
  const BeatSummary& beat = heart.beats().front();
  constexpr double kMl = 1e-6, kMmHg = 133.322387415;
  EXPECT_GT(beat.edv, 100 * kMl);
  EXPECT_GT(beat.ejection_fraction(), 0.6);
  EXPECT_LT(beat.ejection_fraction(), 0.85);
  EXPECT_GT(beat.peak_pressure, 110 * kMmHg);
  EXPECT_LT(beat.peak_pressure, 150 * kMmHg);
  EXPECT_NEAR(beat.arterial_diastolic, 78 * kMmHg, 8 * kMmHg);
}

}  // namespace
}  // namespace gipsi
