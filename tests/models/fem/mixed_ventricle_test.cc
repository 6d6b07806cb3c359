// The truncated ellipsoidal ventricle of the cardiac-mechanics benchmark (Land et al.,
// "Verification of cardiac mechanics software: benchmark problems and solutions for testing
// active and passive material behaviour", Proc. R. Soc. A 471, 2015), problems 2 (passive
// inflation) and 3 (inflation and active contraction), on P2–P1 tets (MixedSolid): the shipped
// scenes `scenes/lv_inflation_p2.json` and `scenes/lv_contraction_p2.json`, mostly on coarser
// meshes and with fewer load increments so that the suite runs them in seconds. They check what the
// mixed element is for: the apex does not depend on κ (locking-free), incompressibility holds,
// and refining the mesh moves the apex little. (The finer runs and their timings are in
// docs/incompressible.md.)

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "gipsi/core/registry.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/fem/mixed_solid.h"
#include "test_paths.h"

namespace gipsi {
namespace {

struct Apex {
  double epi = 0;            // upward (+z) displacement of the epicardial apex (0, 0, −20 mm) [m]
  double endo = 0;           // the same at the endocardial apex (0, 0, −17 mm) [m]
  double volume_change = 0;  // |V / V₀ − 1| of the wall
};

// Runs the shipped scene `file` with its mesh size [m], load increments and volumetric law:
// `kappa_over_c` > 0 makes it nearly incompressible with κ = kappa_over_c · C, 0 keeps it
// fully incompressible.
Apex RunVentricle(const std::string& file, double size, int load_steps, double kappa_over_c) {
  std::ifstream in(std::string(test::SourceDir()) + "/scenes/" + file);
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json scene = nlohmann::json::parse(text.str());
  scene["meshes"]["lv"]["size"] = size;
  nlohmann::json& lv = scene["objects"]["lv"];
  lv["load_steps"] = load_steps;
  if (kappa_over_c > 0) {
    lv["incompressible"] = false;
    lv["material"]["bulk_modulus"] = kappa_over_c * lv["material"]["C"].get<double>();
  }
  scene.erase("outputs");
  scene.erase("probes");
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene loaded = LoadSceneFromString(scene.dump(), file, ".", registry);
  const auto& solid = dynamic_cast<const MixedSolid&>(loaded.kernel->FindObject("lv"));
  const double rest_volume = solid.CurrentVolume();
  const RunResult run = loaded.kernel->Run(loaded.end_time);
  EXPECT_TRUE(run.ok()) << file << " at " << size << " m: " << solid.failure_detail();
  Points apex(3, 2);
  apex << 0, 0, 0, 0, -0.020, -0.017;
  const PointMap map = solid.MapFromNodes(apex);
  EXPECT_LT(map.max_distance(), 1e-9);  // the apexes are vertices of the generated mesh
  Eigen::MatrixXd u(3, solid.domain().num_nodes()), at(3, 2);
  solid.ReadField(solid.FindField("displacement"), u);
  map.Apply(u, at);
  const Apex result{at(2, 0), at(2, 1), std::abs(solid.CurrentVolume() / rest_volume - 1)};
  fmt::print(
      "[ info     ] {} at {} mm, κ/C {}: apex z {:+.4f} mm (epi), {:+.4f} mm (endo), "
      "volume change {:.1e}\n",
      file, size * 1e3, kappa_over_c, result.epi * 1e3, result.endo * 1e3, result.volume_change);
  return result;
}

double Relative(double a, double b) { return std::abs(a / b - 1); }

// Problem 2: isotropic Guccione (C = 10 kPa), 10 kPa on the endocardium, base held, on
// Gmsh's curved (second-order) meshes. The benchmark's codes move the apex down about 8.3 mm
// (epicardium) and 9.6 mm (endocardium), read from their Figs 6–7 to about ±0.1 mm; ours:
// 8.21 and 9.63 mm at 4 mm, 8.24 and 9.64 at 3 mm, 8.25 and 9.65 at 2.5 mm
// (docs/incompressible.md). Asserted: within 1.5 % of the benchmark (the figures' reading);
// a refinement from 4 to 3 mm moves the apex by less than 0.5 %; κ/C = 10³ and 10⁶ give the
// incompressible apex within 0.5 % (the criterion); the incompressible wall keeps its
// volume to 0.1 % at 3 mm, and its change falls under refinement at about the P2 rate
// (1.2e-3 and 7.0e-4: (3/4)² would be 0.56 of it; asserted below 0.75).
TEST(MixedVentricle, InflationApexIsTheBenchmarksIndependentOfKappaAndConverges) {
  const std::string file = "lv_inflation_p2.json";
  const Apex coarse = RunVentricle(file, 0.004, 5, 0);
  const Apex fine = RunVentricle(file, 0.003, 5, 0);
  EXPECT_LT(Relative(-fine.epi, 8.3e-3), 0.015);
  EXPECT_LT(Relative(-fine.endo, 9.6e-3), 0.015);
  EXPECT_LT(Relative(fine.epi, coarse.epi), 0.005);
  EXPECT_LT(Relative(fine.endo, coarse.endo), 0.005);
  EXPECT_LT(fine.volume_change, 1e-3);
  EXPECT_LT(fine.volume_change, 0.75 * coarse.volume_change);
  for (double kappa_over_c : {1e3, 1e6}) {
    const Apex penalty = RunVentricle(file, 0.004, 5, kappa_over_c);
    EXPECT_LT(Relative(penalty.epi, coarse.epi), 0.005) << "κ/C " << kappa_over_c;
    EXPECT_LT(Relative(penalty.endo, coarse.endo), 0.005) << "κ/C " << kappa_over_c;
  }
}

// Problem 3: Guccione (C = 2 kPa, b_f 8, b_t 2, b_fs 4), the benchmark's fibres (helix angle
// +90° to −90° on the ellipsoidal coordinates), 15 kPa inside and 60 kPa of active tension.
// On Gmsh's 4 mm mesh (one or two tets across the 3 mm wall) the answer is not converged (the
// apex rises 4.62 mm; 4.92, 5.07 and 5.16 mm at 3, 2.5 and 2 mm; 4.48 mm once the wall is
// resolved, below), but the formulation's independence of κ already shows: κ/C = 10⁴ and 10⁶
// give the incompressible apex within 0.5 % (the criterion). (The active stress is
// 30 C, so κ/C = 10³ is a compressible wall here, and its apex rightly moves about 1 %.)
TEST(MixedVentricle, ContractionApexIsIndependentOfKappa) {
  const std::string file = "lv_contraction_p2.json";
  const Apex incompressible = RunVentricle(file, 0.004, 10, 0);
  EXPECT_GT(incompressible.epi, 4e-3);  // it rises, by about 4.6 mm
  for (double kappa_over_c : {1e4, 1e6}) {
    const Apex penalty = RunVentricle(file, 0.004, 10, kappa_over_c);
    EXPECT_LT(Relative(penalty.epi, incompressible.epi), 0.005) << "κ/C " << kappa_over_c;
    EXPECT_LT(Relative(penalty.endo, incompressible.endo), 0.005) << "κ/C " << kappa_over_c;
  }
}

// Problem 3 on the shipped scene's 1.5 mm mesh (6k tets, two or three across the wall): the
// wall keeps its volume to 0.1 % when incompressible (the criterion; measured 0.067 %,
// against 0.5 % on every mesh of 2 mm and coarser, where element-level J varies by ±25 % in
// a pattern the linear pressure cannot see), and the apex is within 1 % of the 1.25 mm mesh's
// (4.458 mm epicardium, 4.981 mm endocardium, run by hand: docs/incompressible.md; 1.5 mm
// gives 4.478 and 4.945, differences of 0.45 % and 0.72 %). In 5 load increments (the same
// apex as 10 or 20 to 1e-4 mm): 70 to 225 s on one core (tests/CMakeLists.txt gives it more
// time than the others), so the sanitizer stage skips it
// (scripts/test.sh).
TEST(MixedVentricle, ContractionOnAResolvedWallKeepsItsVolumeAndIsMeshConverged) {
  const Apex resolved = RunVentricle("lv_contraction_p2.json", 0.0015, 5, 0);
  EXPECT_LT(resolved.volume_change, 1e-3);
  EXPECT_LT(Relative(resolved.epi, 4.458e-3), 0.01);
  EXPECT_LT(Relative(resolved.endo, 4.981e-3), 0.01);
}

}  // namespace
}  // namespace gipsi
