// The Heart aggregate and the default demo scene (scenes/heart.json).

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/circulation/circulation.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/heart/heart.h"
#include "io/scene_test_util.h"
#include "test_paths.h"

namespace gipsi {
namespace {

constexpr double kMmHg = 133.322387415, kMl = 1e-6;

std::filesystem::path HeartScene(const char* file = "heart.json") {
  return std::filesystem::path(GIPSI_SOURCE_DIR) / "scenes" / file;
}

/// scenes/heart.json (or another heart scene) loaded with its own registry.
struct HeartRun {
  TypeRegistry registry;
  Scene scene;
  explicit HeartRun(const char* file = "heart.json") {
    RegisterBuiltins(registry);
    scene = LoadScene(HeartScene(file), registry);
  }
  Heart& heart() { return dynamic_cast<Heart&>(scene.kernel->FindObject("heart")); }
  Circulation& blood() { return dynamic_cast<Circulation&>(*heart().FindPart("blood")); }
  FemSolid& muscle() { return dynamic_cast<FemSolid&>(*heart().FindPart("muscle")); }
};

TEST(Heart, DefaultDemoBeatsPhysiologically) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "five coupled beats take minutes under ASan; the release build runs them";
#endif
  HeartRun run;
  Circulation& blood = run.blood();
  FemSolid& muscle = run.muscle();
  const int lv = blood.FindCompartment("lv");
  const double total0 = blood.total_volume();
  // Step by step to 4 s (five beats): the wall always encloses the blood (to its effective
  // compression V p / K, K = 20 MPa: at most 0.1 % here, plus the Newton tolerance).
  const double k = 20e6;
  double worst = 0;
  for (int i = 1; i <= 800; ++i) {
    const RunResult result = run.scene.kernel->Run(0.005 * i);
    ASSERT_TRUE(result.ok()) << result.diagnostic;
    const double p = blood.pressure(lv);
    worst = std::max(worst, std::abs(muscle.CavityVolume(0) - blood.volume(lv) * (1 - p / k)) /
                                blood.volume(lv));
  }
  EXPECT_LT(worst, 1e-6);
  // The closed loop conserves blood (adaptive DP5(4) with event location: round-off).
  EXPECT_NEAR(blood.total_volume(), total0, 1e-12 * total0);
  // Valve events in the physiological cycle after the first beat: mitral closes, aortic opens,
  // aortic closes, mitral opens, and again (the mitral valve may close as atrial systole ends,
  // just before the next stimulus, so the cycle is checked from its first mitral closure).
  std::vector<std::string> order;
  for (const ValveEvent& e : blood.valve_events().Events())
    if (e.time > 0.8)
      order.push_back(blood.valve_name(e.valve) +
                      (e.state == ValveState::kOpen ? " opens" : " closes"));
  const char* expected[4] = {"mitral closes", "aortic opens", "aortic closes", "mitral opens"};
  std::size_t start = 0;
  while (start < order.size() && order[start] != expected[0]) ++start;
  ASSERT_GE(order.size(), start + 12) << "too few valve events after the first beat";
  for (std::size_t i = start; i < order.size(); ++i)
    EXPECT_EQ(order[i], expected[(i - start) % 4]) << i;
  // The summary of the last beat: physiological at rest (REFERENCES.md: aortic about 120/80
  // mmHg, ejection fraction 50–65 %), and periodic to within 2 % beat to beat.
  const std::vector<BeatSummary>& beats = run.heart().beats();
  ASSERT_EQ(beats.size(), 5u);
  const BeatSummary& last = beats.back();
  std::printf(
      "beat 5: EDV %.1f mL, ESV %.1f mL, EF %.1f %%, LV peak %.1f mmHg, aorta %.1f/%.1f "
      "mmHg, change %.2f %%\n",
      last.edv / kMl, last.esv / kMl, 100 * last.ejection_fraction(), last.peak_pressure / kMmHg,
      last.arterial_systolic / kMmHg, last.arterial_diastolic / kMmHg, 100 * last.change);
  EXPECT_GT(last.ejection_fraction(), 0.50);
  EXPECT_LT(last.ejection_fraction(), 0.65);
  EXPECT_NEAR(last.arterial_systolic / kMmHg, 120, 10);
  EXPECT_NEAR(last.arterial_diastolic / kMmHg, 80, 10);
  EXPECT_LT(last.change, 0.02);
}

// scenes/heart_fine.json: the same heart on a muscle and EP mesh 8.6× finer (10,901 tets
// against the default demo's 1,270). Issue 23 asks for the same physiology: EF and pressures
// within 5 % of the coarse heart's, or a difference explained by mesh convergence. At beat 2 the
// EF agrees (64.0 against 65.5 %), but the pressures are 6-8 % higher: the coarse P1 wall is
// stiffer (a nearly incompressible solid on linear tets locks), fills less (EDV 107.9 against
// 121.2 mL) and ejects less into the same arteries. A 4.5-mm mesh between the two shows the
// fine heart's pressures converged (within 0.5 % of it) and the filling converging (EDV 119.0
// mL: the increments 11.1 then 2.2 mL).
// About 25 s in release; scripts/test.sh leaves it out of the ASan stage.
TEST(Heart, FineMeshBeatsLikeTheDefaultDemoAndIsMeshConverged) {
  std::ifstream file(HeartScene("heart_fine.json"));
  const std::string fine_text((std::istreambuf_iterator<char>(file)),
                              std::istreambuf_iterator<char>());
  std::string mid_text = fine_text;
  const std::string fine_size = "\"size\": 0.0036";
  ASSERT_NE(mid_text.find(fine_size), std::string::npos);
  mid_text.replace(mid_text.find(fine_size), fine_size.size(), "\"size\": 0.0045");
  std::vector<BeatSummary> beat2;
  for (int mesh = 0; mesh < 3; ++mesh) {
    TypeRegistry registry;
    RegisterBuiltins(registry);
    const char* names[3] = {"heart.json (8 mm)", "heart_fine.json at 4.5 mm", "heart_fine.json"};
    Scene scene = mesh == 0 ? LoadScene(HeartScene(), registry)
                            : LoadSceneFromString(mesh == 1 ? mid_text : fine_text, names[mesh],
                                                  HeartScene().parent_path(), registry);
    const RunResult result = scene.kernel->Run(1.6);
    ASSERT_TRUE(result.ok()) << names[mesh] << ": " << result.diagnostic;
    const auto& beats = dynamic_cast<Heart&>(scene.kernel->FindObject("heart")).beats();
    ASSERT_EQ(beats.size(), 2u) << names[mesh];
    const BeatSummary& b = beats[1];
    std::printf(
        "%s, beat 2: EDV %.1f mL, ESV %.1f mL, EF %.1f %%, LV peak %.1f mmHg, aorta "
        "%.1f/%.1f mmHg\n",
        names[mesh], b.edv / kMl, b.esv / kMl, 100 * b.ejection_fraction(), b.peak_pressure / kMmHg,
        b.arterial_systolic / kMmHg, b.arterial_diastolic / kMmHg);
    beat2.push_back(b);
  }
  const BeatSummary& coarse = beat2[0];
  const BeatSummary& mid = beat2[1];
  const BeatSummary& fine = beat2[2];
  // The ejection fraction: within 5 % of the default demo's.
  EXPECT_NEAR(fine.ejection_fraction(), coarse.ejection_fraction(),
              0.05 * coarse.ejection_fraction());
  // The pressures: converged between 4.5 and 3.6 mm (within 1.5 %)…
  auto expect_within = [](double a, double b, double fraction, const char* what) {
    EXPECT_NEAR(a, b, fraction * b) << what;
  };
  expect_within(fine.peak_pressure, mid.peak_pressure, 0.015, "peak LV pressure");
  expect_within(fine.arterial_systolic, mid.arterial_systolic, 0.015, "aortic systolic");
  expect_within(fine.arterial_diastolic, mid.arterial_diastolic, 0.015, "aortic diastolic");
  // …the filling converging (the wall less stiff as the mesh refines, by less each time)…
  EXPECT_LT(coarse.edv, mid.edv);
  EXPECT_LT(mid.edv, fine.edv);
  EXPECT_LT(fine.edv - mid.edv, 0.5 * (mid.edv - coarse.edv));
  // …and the coarse heart's pressures off by what its stiffer wall explains: less filling,
  // less ejected (10 % less stroke volume), lower pressures by at most as much.
  const double sv_ratio = coarse.stroke_volume() / fine.stroke_volume();
  EXPECT_LT(sv_ratio, 1.0);
  EXPECT_GT(coarse.peak_pressure / fine.peak_pressure, sv_ratio);
  EXPECT_GT(coarse.arterial_systolic / fine.arterial_systolic, sv_ratio);
}

/// The heart's global field `name` now.
double Read(const Heart& heart, const char* name) {
  Eigen::MatrixXd value(1, 1);
  heart.ReadField(heart.FindField(name), value);
  return value(0, 0);
}

TEST(Heart, BeatFiguresReadNoDataUntilTheirBeatIsComplete) {
  HeartRun run;
  Heart& heart = run.heart();
  const char* figures[] = {
      "end_diastolic_volume",        "end_systolic_volume",   "stroke_volume",
      "ejection_fraction",           "peak_chamber_pressure", "arterial_systolic_pressure",
      "arterial_diastolic_pressure", "cycle_change"};
  for (const char* name : figures)
    EXPECT_EQ(heart.field_info(heart.FindField(name)).no_data, std::optional<double>(kNoBeat))
        << name;
  EXPECT_FALSE(heart.field_info(heart.FindField("beats")).no_data.has_value());
  // Halfway through the first beat nothing is known yet (the figures used to read 0, and the
  // change 1 = "100 % from the previous beat").
  ASSERT_TRUE(run.scene.kernel->Run(0.4).ok());
  EXPECT_EQ(Read(heart, "beats"), 0);
  for (const char* name : figures) EXPECT_EQ(Read(heart, name), kNoBeat) << name;
  // After the first beat: its figures, but no change (no previous beat).
  ASSERT_TRUE(run.scene.kernel->Run(0.85).ok());
  EXPECT_EQ(Read(heart, "beats"), 1);
  EXPECT_GT(Read(heart, "end_diastolic_volume"), 50 * kMl);
  EXPECT_GT(Read(heart, "ejection_fraction"), 0.3);
  EXPECT_EQ(Read(heart, "cycle_change"), kNoBeat);
#if !defined(__SANITIZE_ADDRESS__)  // a second coupled beat takes minutes under ASan
  ASSERT_TRUE(run.scene.kernel->Run(1.65).ok());
  EXPECT_EQ(Read(heart, "beats"), 2);
  EXPECT_GE(Read(heart, "cycle_change"), 0);
  EXPECT_LT(Read(heart, "cycle_change"), 0.5);  // the second beat differs from the first (16 %)
#endif
}

TEST(Heart, ScenePatchesAndBadKeysGetClearErrors) {
  const std::string base = R"({"gipsi": 1, "units": "SI",
    "meshes": {"lv": {"generate": "ellipsoid_shell", "endo": [0.022, 0.048],
                      "epi": [0.032, 0.058], "base_z": 0.012, "size": 0.012}},
    "objects": {"heart": {"type": "Heart", "dt": "5 ms" PATCH}},
    "schedule": {"end": "10 ms"}})";
  auto with = [&](const std::string& patch) {
    std::string text = base;
    text.replace(text.find("PATCH"), 5, patch);
    return testing::SceneLoadError(text);
  };
  EXPECT_EQ(with(""), "(no error)");
  EXPECT_NE(with(R"(, "monitor": {"chamber": "rv"})").find("rv_volume"), std::string::npos);
  EXPECT_NE(with(R"(, "monitr": {})").find("monitr"), std::string::npos);
  EXPECT_NE(with(R"(, "parts": {"muscle": {"material": {"C": -1}}})").find("parts.muscle.material"),
            std::string::npos);
  EXPECT_NE(with(R"(, "connectors": {"cavity_coupling": {"chamber": "aorta"}})")
                .find("must be a chamber"),
            std::string::npos);
}

}  // namespace
}  // namespace gipsi
