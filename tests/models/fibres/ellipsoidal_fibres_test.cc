// Fibres on ellipsoidal coordinates (Land et al. 2015, problem 3): the transmural coordinate and
// the fibre against the parametrisation itself (its derivatives taken by central differences),
// clear errors for bad rules, and the solids that take the rule.

#include "gipsi/models/fibres/ellipsoidal_fibres.h"

#include <cmath>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/fem/mixed_solid.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

// The benchmark's ventricle (m), off the origin to check the centre.
EllipsoidalFibreRule BenchmarkRule() {
  EllipsoidalFibreRule rule;
  rule.centre = Vec3(0.001, -0.002, 0.003);
  rule.endo_short = 0.007;
  rule.endo_long = 0.017;
  rule.epi_short = 0.010;
  rule.epi_long = 0.020;
  return rule;
}

Vec3 Parametrisation(const EllipsoidalFibreRule& rule, double t, double u, double v) {
  const double rs = rule.endo_short + (rule.epi_short - rule.endo_short) * t;
  const double rl = rule.endo_long + (rule.epi_long - rule.endo_long) * t;
  return rule.centre +
         Vec3(rs * std::sin(u) * std::cos(v), rs * std::sin(u) * std::sin(v), rl * std::cos(u));
}

// At points x(t, u, v) through the wall, the rule recovers t, and its fibre is
// sin α ∂x/∂u/|∂x/∂u| + cos α ∂x/∂v/|∂x/∂v| with α = 90° − 180° t, the derivatives taken by
// central differences of x (step 1e-6 rad: their error, about 1e-12 relative, is far below the
// 1e-8 asserted).
TEST(EllipsoidalFibres, RecoverTheCoordinateAndTheBenchmarksFibre) {
  const EllipsoidalFibreRule rule = BenchmarkRule();
  const double h = 1e-6;
  int checked = 0;
  for (double t : {0.0, 0.25, 0.5, 0.8, 1.0})
    for (double u : {-3.1, -2.6, -2.0, -1.4})
      for (double v : {-3.0, -1.0, 0.5, 2.5}) {
        const Vec3 x = Parametrisation(rule, t, u, v);
        const EllipsoidalFibre got = EllipsoidalFibreAt(rule, x);
        EXPECT_NEAR(got.t, t, 1e-12) << u << " " << v;
        const Vec3 du =
            (Parametrisation(rule, t, u + h, v) - Parametrisation(rule, t, u - h, v)) / (2 * h);
        const Vec3 dv =
            (Parametrisation(rule, t, u, v + h) - Parametrisation(rule, t, u, v - h)) / (2 * h);
        const double alpha = (90 - 180 * t) * std::numbers::pi / 180;
        const Vec3 expected = std::sin(alpha) * du.normalized() + std::cos(alpha) * dv.normalized();
        EXPECT_LT((got.fibre - expected).norm(), 1e-8) << t << " " << u << " " << v;
        ++checked;
      }
  EXPECT_EQ(checked, 80);
  // Just outside the wall t leaves [0, 1] and the angle is the nearer surface's.
  const EllipsoidalFibre outside = EllipsoidalFibreAt(rule, Parametrisation(rule, 1.05, -2, 1));
  EXPECT_NEAR(outside.t, 1.05, 1e-12);
  EXPECT_LT(
      (outside.fibre - EllipsoidalFibreAt(rule, Parametrisation(rule, 1, -2, 1)).fibre).norm(),
      0.05);
  // On the axis (the apex) v is taken as 0, and the fibre is still a unit vector.
  const EllipsoidalFibre apex = EllipsoidalFibreAt(rule, rule.centre - Vec3(0, 0, 0.0185));
  EXPECT_NEAR(apex.t, 0.5, 1e-12);
  EXPECT_NEAR(apex.fibre.norm(), 1, 1e-12);
}

TEST(EllipsoidalFibres, BadRulesGetAClearError) {
  auto parse = [](const std::string& text) {
    const JsonDocument doc = JsonDocument::Parse(text, "scene.json");
    return ParseEllipsoidalFibreRule(doc.root().At("fibres"));
  };
  const std::string good = R"("rule": "ellipsoidal", "endo": [0.007, 0.017], "epi": )";
  auto error = [&](const std::string& text) -> std::string {
    try {
      (void)parse(text);
    } catch (const InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NO_THROW((void)parse(R"({"fibres": {)" + good + R"([0.01, 0.02]}})"));
  EXPECT_THAT(error(R"({"fibres": {)" + good + R"([0.006, 0.02]}})"),
              HasSubstr("scene.json: fibres.epi: expected radii larger than the endocardium's"));
  EXPECT_THAT(error(R"({"fibres": {)" + good + R"([0.01]}})"),
              HasSubstr("fibres.epi: expected [short radius, long radius]"));
  EXPECT_THAT(error(R"({"fibres": {)" + good + R"([0.01, 0.02], "endo_angle": 120}})"),
              HasSubstr("fibres.endo_angle: expected a helix angle in degrees within [-90, 90]"));
  EXPECT_THAT(error(R"({"fibres": {)" + good + R"([0.01, 0.02], "axis": [0, 0, 1]}})"),
              HasSubstr("fibres: unknown key 'axis'"));
}

// Through the scene: a MixedSolid takes the rule at each quadrature point (where the
// curved element puts it), a FemSolid at each tet's centroid.
TEST(EllipsoidalFibres, SolidsTakeTheRulesFibres) {
  const std::string fibres =
      R"("fibres": {"rule": "ellipsoidal", "endo": [0.007, 0.017], "epi": [0.010, 0.020]})";
  const std::string material =
      R"("material": {"law": "Guccione", "C": 2000, "bf": 8, "bt": 2, "bfs": 4,
                      "bulk_modulus": 2e6}, )";
  const std::string text = R"({
  "gipsi": 1,
  "meshes": {"lv": {"generate": "ellipsoid_shell", "endo": [0.007, 0.017], "epi": [0.010, 0.020],
                    "base_z": 0.005, "size": 0.004, "order": 2}},
  "objects": {
    "mixed": {"type": "MixedSolid", "domain": "lv", "dt": 1, "incompressible": true, )" +
                           material + fibres + R"(},
    "penalty": {"type": "FemSolid", "domain": "lv", "dt": 1, "gravity": [0, 0, 0], )" +
                           material + fibres + R"(}
  },
  "schedule": {"end": 1}
})";
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(text, "scene.json", ".", registry);
  EllipsoidalFibreRule rule = BenchmarkRule();
  rule.centre.setZero();
  const auto& mixed = dynamic_cast<const MixedSolid&>(scene.kernel->FindObject("mixed"));
  double worst = 0;
  for (Index e = 0; e < mixed.domain().num_tets(); ++e)
    for (int q = 0; q < 4; ++q) {
      const Vec3 expected = EllipsoidalFibreAt(rule, mixed.QuadraturePoint(e, q)).fibre;
      worst = std::max(worst, (mixed.axes_at(e, q).col(0) - expected).norm());
    }
  EXPECT_LT(worst, 1e-12);
  const SimObject& penalty = scene.kernel->FindObject("penalty");
  const Mesh& mesh = penalty.domain();
  Eigen::MatrixXd got(3, mesh.num_tets());
  penalty.ReadField(penalty.FindField("fibre"), got);
  for (Index e = 0; e < mesh.num_tets(); ++e) {
    Vec3 centroid = Vec3::Zero();
    for (int a = 0; a < 4; ++a) centroid += 0.25 * mesh.nodes.col(mesh.tets(a, e));
    EXPECT_LT((got.col(e) - EllipsoidalFibreAt(rule, centroid).fibre).norm(), 1e-12) << e;
  }
}

}  // namespace
}  // namespace gipsi
