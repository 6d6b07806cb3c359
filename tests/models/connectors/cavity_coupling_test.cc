// The monolithic cavity coupling: FemSolid solving its wall together with a blood law
// (cavity_law.h), and the CavityCoupling connector to the lumped circulation.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "gipsi/geometry/generators.h"
#include "gipsi/models/connectors/cavity_coupling.h"
#include "gipsi/models/fem/fem_solid.h"
#include "models/circulation/circulation_test_util.h"
#include "models/fem/fem_test_util.h"

namespace gipsi {
namespace {

using testing::AccurateParams;
using testing::VerticesWhere;

constexpr double kA = 1, kB = 2, kH = 0.3;  // thick cylinder: inner, outer radius, height [m]

/// A plane-strain thick cylinder (ends held axially, rigid modes held) with a lumen cavity, as
/// in the FemSolid Lamé test; circumferential fibres for active tension.
std::unique_ptr<FemSolid> MakeCylinder() {
  auto mesh = std::make_shared<const Mesh>(MakeCylinderShell(kA, kB, kH, 0.15));
  FemParams params =
      AccurateParams(R"({"law": "Linear", "youngs_modulus": 1e6, "poisson_ratio": 0.3})",
                     ImplicitSchemeKind::kStatic);
  params.cavities.push_back(CavitySpec{"lumen", GroupRegion{"inner"}});
  auto fem = std::make_unique<FemSolid>("cylinder", mesh, params);
  auto& bcs = fem->boundary_conditions();
  for (Index j : VerticesWhere(*fem, [&](const Vec3& X) {
         return std::abs(X.z()) < 1e-9 || std::abs(X.z() - kH) < 1e-9;
       }))
    bcs.Fix(j, 4);
  const std::pair<Vec3, AxisMask> holds[3] = {
      {Vec3(kB, 0, 0), 2}, {Vec3(-kB, 0, 0), 2}, {Vec3(0, kB, 0), 1}};
  for (const auto& [target, mask] : holds) {
    Index best = 0;
    double dist = 1e30;
    for (Index j = 0; j < fem->boundary().num_vertices(); ++j) {
      const Vec3 X = mesh->nodes.col(fem->boundary().vertex_to_node[static_cast<std::size_t>(j)]);
      const double d = (X.head<2>() - target.head<2>()).norm();
      if (d < dist) dist = d, best = j;
    }
    bcs.Fix(best, mask);
  }
  Eigen::MatrixXd fibres(3, fem->num_elements());
  for (Index e = 0; e < fem->num_elements(); ++e) {
    Vec3 c = Vec3::Zero();
    for (int a = 0; a < 4; ++a) c += 0.25 * mesh->nodes.col(mesh->tets(a, e));
    fibres.col(e) = Vec3(-c.y(), c.x(), 0).normalized();
  }
  fem->WriteField(fem->FindField("fibre"), fibres);
  return fem;
}

double Read(const SimObject& o, const std::string& field) {
  Eigen::MatrixXd v(1, 1);
  o.ReadField(o.FindField(field), v);
  return v(0, 0);
}

void Write(SimObject& o, const std::string& field, double value) {
  Eigen::MatrixXd v = Eigen::MatrixXd::Constant(1, 1, value);
  o.WriteField(o.FindField(field), v);
}

void SetTension(FemSolid& fem, double t) {
  fem.WriteField(fem.FindField("active_tension"),
                 Eigen::MatrixXd::Constant(1, fem.num_elements(), t));
}

/// V_b(p) = V_a − C (p − p_a): a linear blood compliance, counting its calls.
class LinearLaw final : public CavityLaw {
 public:
  LinearLaw(double v_a, double c, double p_a) : v_a_(v_a), c_(c), p_a_(p_a) {}
  bool EndVolume(double, double, double p, double& v) override {
    ++calls;
    v = v_a_ - c_ * (p - p_a_);
    return true;
  }
  int calls = 0;

 private:
  double v_a_, c_, p_a_;
};

TEST(CoupledCavity, SolvesWallAndBloodTogether) {
  // The law asks for more volume than the cavity has: the coupled step must land on a state
  // that is (1) on the law, V = V_b(p*), to the root finder's tolerance (1e-13 relative), and
  // (2) the wall's equilibrium under p*: the same solid loaded by p* as a plain follower
  // pressure reaches the same volume (to the Newton tolerance, 1e-10 of the load: ~1e-9 of
  // the volume change).
  auto coupled = MakeCylinder();
  const double v0 = Read(*coupled, "lumen_volume");
  // Lamé: volume change per Pa of lumen pressure (plane strain), to size the law.
  const double e = 1e6, nu = 0.3;
  const double s = 2 * std::numbers::pi * kA * kH * (1 + nu) * kA * kA / (e * (kB * kB - kA * kA)) *
                   ((1 - 2 * nu) * kA + kB * kB / kA);
  LinearLaw law(v0 + 2e3 * s, 0.5 * s, 0);  // p* ≈ 2e3 / 1.5 ≈ 1.3 kPa
  coupled->AttachCavityLaw("lumen", &law);
  ASSERT_TRUE(coupled->Step(1.0).ok()) << coupled->failure_detail();
  const double p = Read(*coupled, "lumen_pressure");
  const double v = Read(*coupled, "lumen_volume");
  std::printf("coupled: p* = %.6f Pa, V - V0 = %.6e m^3, Newton iterations %d, law calls %d\n", p,
              v - v0, coupled->last_newton().iterations, law.calls);
  EXPECT_NEAR(v, v0 + 2e3 * s - 0.5 * s * p, 1e-12 * v0);
  EXPECT_NEAR(p, 2e3 / 1.5, 0.05 * 2e3 / 1.5);  // P1 stiffness is within a few % of Lamé

  auto loaded = MakeCylinder();
  Write(*loaded, "lumen_pressure", p);
  ASSERT_TRUE(loaded->Step(1.0).ok()) << loaded->failure_detail();
  EXPECT_NEAR(Read(*loaded, "lumen_volume") - v0, v - v0, 1e-8 * std::abs(v - v0));
  // Newton with the rank-one tangent converges as fast as the plain pressure load (linear
  // material, follower load): a missing or wrong ∂p/∂u term would need many more iterations.
  std::printf("pressure-loaded: Newton iterations %d\n", loaded->last_newton().iterations);
  EXPECT_LE(coupled->last_newton().iterations, loaded->last_newton().iterations + 1);
}

/// Closed valves: the blood volume is fixed, compressible with bulk modulus K.
class ClosedLaw final : public CavityLaw {
 public:
  ClosedLaw(double v, double k) : v_(v), k_(k) {}
  bool EndVolume(double, double, double p, double& v) override {
    v = v_ * (1 - p / k_);
    return true;
  }

 private:
  double v_, k_;
};

TEST(CoupledCavity, ClosedCavityHoldsItsVolumeWhileTheWallContracts) {
  // Active circumferential tension squeezes the lumen; with the blood trapped (K = 2.2 GPa)
  // the pressure rises instead and the volume stays within V0 p / K (the blood's compression)
  // plus the root finder's 1e-13 V0.
  const double k = 2.2e9;
  auto fem = MakeCylinder();
  const double v0 = Read(*fem, "lumen_volume");
  ClosedLaw law(v0, k);
  fem->AttachCavityLaw("lumen", &law);
  double last_p = 0;
  for (int step = 1; step <= 4; ++step) {
    SetTension(*fem, 5e4 * step);
    ASSERT_TRUE(fem->Step(1.0).ok()) << fem->failure_detail();
    const double p = Read(*fem, "lumen_pressure");
    const double v = Read(*fem, "lumen_volume");
    std::printf("T_a = %.0f kPa: p = %.3f kPa, (V - V0)/V0 = %.3e, Newton %d\n", 50.0 * step,
                1e-3 * p, (v - v0) / v0, fem->last_newton().iterations);
    EXPECT_GT(p, last_p);
    EXPECT_NEAR(v, v0 * (1 - p / k), 1e-13 * v0 + 1e-12 * v0);
    last_p = p;
  }
  // Laplace for a thick cylinder with uniform circumferential tension T (the wall's hoop force
  // T (b − a) per unit height balances p · a): p ≈ T (b − a) / a = T; linear elasticity adds the
  // radial stress of the constrained wall, so only the order is checked (within 30 %).
  EXPECT_NEAR(last_p, 2e5, 0.3 * 2e5);
}

std::unique_ptr<FemSolid> MakeVentricle(double size) {
  EllipsoidShellSpec spec{.endo_short = 0.022,
                          .endo_long = 0.048,
                          .epi_short = 0.032,
                          .epi_long = 0.058,
                          .base_z = 0.012,
                          .mesh_size = size};
  auto mesh = std::make_shared<const Mesh>(MakeEllipsoidShell(spec));
  FemParams params =
      AccurateParams(R"({"law": "Linear", "youngs_modulus": 1e5, "poisson_ratio": 0.3})",
                     ImplicitSchemeKind::kStatic);
  params.cavities.push_back(CavitySpec{"lumen", GroupRegion{"endo"}});
  auto fem = std::make_unique<FemSolid>("lv", mesh, params);
  for (Index j : VerticesWhere(*fem, [](const Vec3& X) { return X.z() > 0.012 - 1e-9; }))
    fem->boundary_conditions().Fix(j, 7);
  return fem;
}

TEST(CavityVolume, TruncatedEllipsoidConvergesToTheClosedForm) {
  // π a² ∫_{−c}^{z0} (1 − z²/c²) dz for the endocardium (a = 22, c = 48, z0 = 12 mm). The
  // inscribed facets miss O(h²) of it: the error must shrink about 4× when h halves (at least
  // 2.5×, allowing for Gmsh's irregular meshes) and be under 3 % on the finer mesh.
  const double a = 0.022, c = 0.048, z0 = 0.012;
  const double exact = std::numbers::pi * a * a * (z0 - z0 * z0 * z0 / (3 * c * c) + 2 * c / 3);
  double errors[2];
  const double sizes[2] = {0.008, 0.004};
  for (int k = 0; k < 2; ++k) {
    auto fem = MakeVentricle(sizes[k]);
    errors[k] = std::abs(Read(*fem, "lumen_volume") - exact) / exact;
    std::printf("h = %.0f mm: cavity volume error %.3f %%\n", 1e3 * sizes[k], 100 * errors[k]);
  }
  EXPECT_LT(errors[1], 0.03);
  EXPECT_GT(errors[0] / errors[1], 2.5);
}

TEST(CavityPressure, BaseReactionBalancesPressureTimesTheOpening) {
  // A cavity pressure p on the open endocardium pushes the cup towards its apex (−z) with
  // p × (the rim polygon's area): the pressure on the walls sums to −p A ẑ because the opening
  // carries none. In static equilibrium the held base pulls back with exactly +p A ẑ (any
  // material, any mesh), to the Newton tolerance.
  auto fem = MakeVentricle(0.008);
  const double p = 500;
  Write(*fem, "lumen_pressure", p);
  ASSERT_TRUE(fem->Step(1.0).ok()) << fem->failure_detail();
  Eigen::MatrixXd reactions(3, fem->boundary().num_vertices());
  fem->ReadField(fem->FindField("reaction_force"), reactions);
  // The rim: base vertices on the endocardium (r ≈ the endocardial radius at z0).
  const double r_rim = 0.022 * std::sqrt(1 - 0.012 * 0.012 / (0.048 * 0.048));
  std::vector<std::pair<double, Vec3>> rim;
  for (Index j : VerticesWhere(*fem, [&](const Vec3& X) {
         return X.z() > 0.012 - 1e-9 && std::abs(X.head<2>().norm() - r_rim) < 1e-6;
       })) {
    const Vec3 X =
        fem->domain().nodes.col(fem->boundary().vertex_to_node[static_cast<std::size_t>(j)]);
    rim.push_back({std::atan2(X.y(), X.x()), X});
  }
  ASSERT_GT(rim.size(), 8u);
  std::sort(rim.begin(), rim.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
  double area = 0;  // shoelace
  for (std::size_t i = 0; i < rim.size(); ++i) {
    const Vec3& u = rim[i].second;
    const Vec3& v = rim[(i + 1) % rim.size()].second;
    area += 0.5 * (u.x() * v.y() - v.x() * u.y());
  }
  const Vec3 total = reactions.rowwise().sum();
  std::printf("base reaction %.6f N, p x opening %.6f N\n", total.z(), p * area);
  EXPECT_NEAR(total.z(), p * area, 1e-6 * p * area);
  EXPECT_NEAR(total.head<2>().norm(), 0, 1e-6 * p * area);
}

// A cylinder ventricle ejecting into a compliance through a valve, driven by a ramp of active
// tension: the circulation object, the CavityCoupling connector and the kernel's order.
constexpr const char* kEjectionScene = R"({
  "gipsi": 1, "units": "SI",
  "meshes": {"cyl": {"generate": "cylinder_shell", "inner_radius": 0.02, "outer_radius": 0.03,
                     "height": 0.02, "size": 0.005}},
  "objects": {
    "wall": {"type": "FemSolid", "domain": "cyl", "dt": "5 ms",
             "material": {"law": "NeoHookean", "youngs_modulus": 1e5, "poisson_ratio": 0.3},
             "fibres": {"rule": "transmural", "endo": {"group": "inner"}, "epi": {"group": "outer"},
                        "axis": [0, 0, 1], "endo_angle": 0, "epi_angle": 0},
             "integrator": "Static", "gravity": [0, 0, 0], "linear_solver": {"type": "ldlt"},
             "newton": {"tolerance": 1e-10},
             "cavities": {"lumen": {"group": "inner"}},
             "boundary_conditions": [{"name": "bottom", "region": {"group": "bottom"}, "fix": ["z"]},
                                     {"name": "top", "region": {"group": "top"}, "fix": ["z"]},
                                     {"name": "pin", "region": {"sphere": {"center": [0.03, 0, 0], "radius": 0.004}}, "fix": ["y"]},
                                     {"name": "pin2", "region": {"sphere": {"center": [0, 0.03, 0], "radius": 0.004}}, "fix": ["x"]}]},
    "blood": {"type": "Circulation", "dt": "5 ms",
              "compartments": {
                "lv": {"type": "chamber", "driven_by": "pressure", "volume": "20 mL"},
                "aorta": {"type": "compliance", "compliance": "0.5 mL/mmHg", "pressure": "60 mmHg"},
                "atrium": {"type": "reservoir", "pressure": "-5 mmHg"}},
              "connections": {
                "mitral": {"type": "valve", "from": "atrium", "to": "lv", "resistance": "0.01 mmHg*s/mL"},
                "aortic": {"type": "valve", "from": "lv", "to": "aorta", "resistance": "0.1 mmHg*s/mL"},
                "periphery": {"type": "resistor", "from": "aorta", "to": "atrium", "resistance": "50 mmHg*s/mL"}},
              "log_events": false}
  },
  "connectors": {"coupling": {"type": "CavityCoupling", "wall": "wall", "cavity": "lumen",
                              "blood": "blood", "chamber": "lv"}},
  "schedule": {"end": "0.3 s", "order": ["wall", "coupling", "blood"]}
})";

TEST(CavityCoupling, IsovolumetricContractionThenEjection) {
  SceneHolder holder(kEjectionScene);
  Kernel& kernel = *holder.scene().kernel;
  auto& wall = dynamic_cast<FemSolid&>(kernel.FindObject("wall"));
  Circulation& blood = holder.Object("blood");
  const int lv = blood.FindCompartment("lv");
  const double k = 2.2e9;
  const double v0 = Read(wall, "lumen_volume");
  // The connector filled the chamber with the cavity's volume.
  EXPECT_NEAR(blood.volume(lv), v0, 1e-15);
  const double total0 = blood.total_volume();
  double last_p = -1;
  bool ejected = false;
  int isovolumetric_steps = 0;
  for (int step = 1; step <= 60; ++step) {
    const double t = 0.005 * step;
    SetTension(wall, 2e5 * t);  // 60 kPa at 0.3 s
    const RunResult result = kernel.Run(t);
    ASSERT_TRUE(result.ok()) << result.diagnostic;
    const double p = blood.pressure(lv);
    const double v_wall = Read(wall, "lumen_volume");
    // Every step: the wall encloses exactly the (compressed) blood, to the wall's Newton
    // tolerance (on its residual and on the pressure's volume residual, newton.md).
    EXPECT_NEAR(v_wall, blood.volume(lv) * (1 - p / k), 1e-11 * v0) << "t = " << t;
    EXPECT_NEAR(Read(wall, "lumen_pressure"), p, 1e-9 * std::abs(p) + 1e-9);
    const bool open = Read(blood, "aortic_open") > 0.5;
    if (!open && !ejected) {
      // Isovolumetric: the volume held to the blood's compression, the pressure rising
      // monotonically (no oscillation).
      ++isovolumetric_steps;
      EXPECT_NEAR(v_wall, v0 * (1 - p / k), 1e-11 * v0) << "t = " << t;
      EXPECT_GT(p, last_p) << "t = " << t;
    }
    if (open) ejected = true;
    last_p = p;
  }
  std::printf(
      "isovolumetric steps %d; final LV volume %.3f mL of %.3f; LV pressure %.1f mmHg; "
      "Newton iterations %lld, factorisations %lld\n",
      isovolumetric_steps, blood.volume(lv) / kMl, v0 / kMl, last_p / kMmHg,
      static_cast<long long>(wall.profile().newton_iterations),
      static_cast<long long>(wall.profile().factorizations));
  EXPECT_TRUE(ejected);
  EXPECT_GT(isovolumetric_steps, 3);
  EXPECT_LT(blood.volume(lv), 0.95 * v0);  // it ejected a noticeable volume
  // The closed circuit (reservoir counting what flowed in) conserves blood to round-off.
  EXPECT_NEAR(blood.total_volume(), total0, 1e-12 * total0);
}

TEST(CavityCoupling, AScheduleItsOrderRuleRefusesIsRefusedBeforeTheFirstStep) {
  auto replaced = [](const std::string& from, const std::string& to) {
    std::string t = kEjectionScene;
    t.replace(t.find(from), from.size(), to);
    return testing::SceneLoadError(t);
  };
  // The connector before the wall: the blood would not wait for the wall's pressure.
  const std::string before = replaced(R"("order": ["wall", "coupling", "blood"])",
                                      R"("order": ["coupling", "wall", "blood"])");
  EXPECT_NE(before.find("schedule.order: connector 'coupling' (CavityCoupling) must fire after "
                        "'wall' steps and before 'blood' steps"),
            std::string::npos)
      << before;
  EXPECT_NE(before.find("the order [coupling, wall, blood]"), std::string::npos) << before;
  // No order at all: the default (connectors first) is refused the same way, at the connector.
  const std::string unordered = replaced(R"(, "order": ["wall", "coupling", "blood"])", "");
  EXPECT_NE(unordered.find("connectors.coupling: connector 'coupling' (CavityCoupling) must "
                           "fire after 'wall' steps"),
            std::string::npos)
      << unordered;
  EXPECT_NE(unordered.find("the default order"), std::string::npos) << unordered;
  // Blood on another time step, and a connector that skips macro steps.
  const std::string other_dt = replaced(R"("blood": {"type": "Circulation", "dt": "5 ms")",
                                        R"("blood": {"type": "Circulation", "dt": "2.5 ms")");
  EXPECT_NE(other_dt.find("needs 'wall' and 'blood' to step with the same time step"),
            std::string::npos)
      << other_dt;
  const std::string skipping = replaced(R"("chamber": "lv"})", R"("chamber": "lv", "every": 2})");
  EXPECT_NE(skipping.find("must fire every macro step"), std::string::npos) << skipping;
}

TEST(CavityCoupling, BadWiringGetsAClearError) {
  std::string text = kEjectionScene;
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    t.replace(t.find(from), from.size(), to);
    return testing::SceneLoadError(t);
  };
  EXPECT_NE(replaced(R"("cavity": "lumen")", R"("cavity": "lumn")").find("no cavity 'lumn'"),
            std::string::npos);
  EXPECT_NE(replaced(R"("chamber": "lv")", R"("chamber": "aorta")").find("must be a chamber"),
            std::string::npos);
  // Blood without the LumpedChambers capability is refused at its key.
  const std::string no_chambers =
      replaced(R"("blood": "blood", "chamber")", R"("blood": "wall", "chamber")");
  EXPECT_NE(no_chambers.find("connectors.coupling.blood: object 'wall' (FemSolid) has no lumped "
                             "chambers"),
            std::string::npos)
      << no_chambers;
  // A wall of a type without cavities (the CavityWall capability) is refused at its key.
  const std::string no_cavities = replaced(R"("wall": "wall")", R"("wall": "blood")");
  EXPECT_NE(no_cavities.find("connectors.coupling.wall"), std::string::npos) << no_cavities;
  EXPECT_NE(no_cavities.find("object 'blood' (Circulation) has no cavities to couple to blood"),
            std::string::npos)
      << no_cavities;
}

}  // namespace
}  // namespace gipsi
