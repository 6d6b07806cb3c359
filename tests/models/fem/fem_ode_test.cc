// FemSolid through the OdeSystem contract (fem_solid_ode.cc): any one-step integrator steps
// u̇ = v, v̇ = M_L⁻¹(f_ext − f_int − C v). Checked against the integrator's own order, against
// FemSolid's implicit Newmark scheme on the same semi-discrete equations, and for exact
// kinematic constraints; and the combinations it cannot serve are refused with clear errors.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "gipsi/base/error.h"
#include "gipsi/models/fem/fem_solid.h"
#include "io/scene_test_util.h"
#include "models/fem/fem_test_util.h"

namespace gipsi {
namespace {

using testing::AccurateParams;
using ::testing::HasSubstr;
using testing::VerticesWhere;

constexpr const char* kCorotational =
    R"({"law": "Corotational", "youngs_modulus": 1e5, "poisson_ratio": 0.3})";

/// A clamped 1 × 0.1 × 0.1 m beam (8 cells) under gravity with Rayleigh damping (α 0.5/s,
/// β 1e-4 s), released with a bending-shaped velocity of 2 m/s at the tip (large rotations for
/// the corotational law): stepped by `integrator`, or by Newmark if null.
std::unique_ptr<FemSolid> Beam(std::unique_ptr<OdeIntegrator> integrator) {
  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3(1, 0.1, 0.1), {8, 1, 1}));
  FemParams params = AccurateParams(kCorotational, ImplicitSchemeKind::kNewmark);
  params.lumped_mass = true;
  params.gravity = Vec3(0, 0, -9.81);
  params.rayleigh_mass = 0.5;
  params.rayleigh_stiffness = 1e-4;
  auto fem = integrator ? std::make_unique<FemSolid>("beam", mesh, params, std::move(integrator))
                        : std::make_unique<FemSolid>("beam", mesh, params);
  for (Index j : VerticesWhere(*fem, [](const Vec3& X) { return X.x() == 0; }))
    fem->boundary_conditions().Fix(j);
  Points v = Points::Zero(3, mesh->num_nodes());
  for (Index i = 0; i < mesh->num_nodes(); ++i) v(2, i) = 2.0 * std::pow(mesh->nodes(0, i), 2);
  fem->WriteField(fem->FindField("velocity"), v);
  return fem;
}

/// Displacements after `steps` steps of `dt`.
VecX Advance(FemSolid& fem, int steps, double dt) {
  for (int k = 0; k < steps; ++k) {
    const StepStatus status = fem.Step(dt);
    EXPECT_TRUE(status.ok()) << status.what << " " << fem.failure_detail();
    if (!status.ok()) break;
  }
  return fem.u();
}

TEST(FemOde, RungeKutta4IsFourthOrderOnANonlinearBeam) {
  // Errors against the next finer step, e(h) = |u_h − u_{h/2}|, fall as h⁴: e(h)/e(h/2) = 16
  // asymptotically. The steps (1/4 to 1/16 of the explicit estimate) keep the error far above
  // round-off (1e-15 of the 0.1 m motion) and in the asymptotic range.
  const double limit = Beam(std::make_unique<RungeKutta4>())->stable_dt_estimate();
  ASSERT_GT(limit, 1e-5);
  ASSERT_LT(limit, 1e-2);
  const double t_end = 0.05;
  const int base = static_cast<int>(std::ceil(t_end / (0.25 * limit)));
  VecX u[3];
  for (int level = 0; level < 3; ++level) {
    const int steps = base << level;
    u[level] = Advance(*Beam(std::make_unique<RungeKutta4>()), steps, t_end / steps);
  }
  const double moved = u[2].norm();
  ASSERT_GT(moved, 1e-3);  // the beam moved visibly
  const double e0 = (u[0] - u[1]).norm(), e1 = (u[1] - u[2]).norm();
  const double order = std::log2(e0 / e1);
  std::printf("dt limit %.3g s; e(h) %.3e, e(h/2) %.3e m: order %.2f\n", limit, e0, e1, order);
  EXPECT_NEAR(order, 4.0, 0.3);
}

TEST(FemOde, AgreesWithTheImplicitNewmarkSchemeOnTheSameEquations) {
  // Newmark (average acceleration, second order) solves the same semi-discrete equations with
  // an assembled tangent and Newton; RK4 at a quarter of the stability estimate is four orders
  // more accurate. So Newmark's distance from RK4 must fall by 4 when its step halves, and at
  // the finer step be a small fraction of the motion: the derivative RK4 integrates carries the
  // same inertia, damping (both Rayleigh terms), gravity and clamp. (Newmark freezes β's
  // tangent at the step's start, a first-order term; at β = 1e-4 s it stays far below the
  // second-order error here, and the ratio shows it.)
  const double t_end = 0.05;
  auto rk4 = Beam(std::make_unique<RungeKutta4>());
  const int steps = static_cast<int>(std::ceil(t_end / (0.25 * rk4->stable_dt_estimate())));
  const VecX reference = Advance(*rk4, steps, t_end / steps);
  const VecX coarse = Advance(*Beam(nullptr), 50, t_end / 50);
  const VecX fine = Advance(*Beam(nullptr), 100, t_end / 100);
  const double d_coarse = (coarse - reference).norm(), d_fine = (fine - reference).norm();
  std::printf("|Newmark - RK4|: %.3e m at dt %.1e, %.3e m at dt %.1e (motion %.3e m)\n", d_coarse,
              t_end / 50, d_fine, t_end / 100, reference.norm());
  EXPECT_NEAR(d_coarse / d_fine, 4.0, 0.5);
  EXPECT_LT(d_fine, 1e-2 * reference.norm());
}

TEST(FemOde, KinematicConstraintsAreExactAndTheUnconstrainedEnergyIsConserved) {
  // The end face driven by a displacement ramp and a velocity: after every step the driven
  // axes sit exactly on their targets. Then released and undamped, RK4 keeps ½vᵀMv + strain
  // energy within its own dissipation: on a mode of frequency ω its amplification factor is
  // |R(iωh)|² = 1 − (ωh)⁶/72 + O((ωh)⁸), and ωh <= 2h/limit for every mode (the limit is
  // 2/ω_max or less), so k steps lose at most k (2h/limit)⁶/72 of the energy.
  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3(1, 0.1, 0.1), {8, 1, 1}));
  FemParams params = AccurateParams(kCorotational, ImplicitSchemeKind::kBackwardEuler);
  params.lumped_mass = true;
  FemSolid fem("beam", mesh, params, std::make_unique<RungeKutta4>());
  const auto clamp = VerticesWhere(fem, [](const Vec3& X) { return X.x() == 0; });
  const auto tip = VerticesWhere(fem, [](const Vec3& X) { return X.x() == 1; });
  for (Index j : clamp) fem.boundary_conditions().Fix(j);
  const double dt = 0.25 * fem.stable_dt_estimate();
  const auto& v2n = fem.boundary().vertex_to_node;
  for (int k = 1; k <= 40; ++k) {
    for (Index j : tip) {
      fem.boundary_conditions().PrescribeDisplacement(j, Vec3(0, 0, 1e-3 * k), AxisMask{4});
      fem.boundary_conditions().PrescribeVelocity(j, Vec3(0.01, 0, 0), AxisMask{1});
    }
    const double x_before = fem.x()[3 * v2n[static_cast<std::size_t>(tip[0])]];
    ASSERT_TRUE(fem.Step(dt).ok()) << fem.failure_detail();
    for (Index j : tip) {
      const Index node = v2n[static_cast<std::size_t>(j)];
      EXPECT_EQ(fem.u()[3 * node + 2], 1e-3 * k);
      EXPECT_DOUBLE_EQ(fem.v()[3 * node], 0.01);
    }
    EXPECT_NEAR(fem.x()[3 * v2n[static_cast<std::size_t>(tip[0])]], x_before + 0.01 * dt, 1e-15);
  }
  for (Index j : tip) fem.boundary_conditions().Release(j);
  const double e0 = fem.KineticEnergy() + fem.StrainEnergy();
  ASSERT_GT(e0, 0);
  const int steps = 400;
  const double h = dt / 4;  // ωh <= 1/8
  double worst = 0;
  for (int k = 0; k < steps; ++k) {
    ASSERT_TRUE(fem.Step(h).ok()) << fem.failure_detail();
    worst = std::max(worst, std::abs(fem.KineticEnergy() + fem.StrainEnergy() - e0) / e0);
  }
  const double bound = steps * std::pow(2 * h / fem.stable_dt_estimate(), 6) / 72;
  std::printf("energy drift over %d RK4 steps: %.2e (bound %.2e)\n", steps, worst, bound);
  EXPECT_LT(worst, bound);
}

TEST(FemOde, AnInvertedElementFailsTheStepAndKeepsItsStartingState) {
  // Far beyond the stability limit the explicit step blows up; the neo-Hookean law has no
  // state with det F <= 0, so a stage meets an inverted element: the step fails, naming it, and
  // the object keeps the state it had (the kernel's retry halves the step from there). The tet
  // is named by its id in the mesh file (here made-up Gmsh tags 1001, 1002, …).
  Mesh box = MakeTetBox(Vec3::Zero(), Vec3(1, 0.1, 0.1), {8, 1, 1});
  for (Index e = 0; e < box.num_tets(); ++e) box.tet_ids.push_back(1001 + e);
  box.tet_id_kind = "Gmsh element tag";
  auto mesh = std::make_shared<const Mesh>(std::move(box));
  FemParams params =
      AccurateParams(R"({"law": "NeoHookean", "youngs_modulus": 1e5, "poisson_ratio": 0.3})",
                     ImplicitSchemeKind::kBackwardEuler);
  params.lumped_mass = true;
  params.gravity = Vec3(0, 0, -9.81);
  FemSolid fem("beam", mesh, params, std::make_unique<SymplecticEuler>());
  for (Index j : VerticesWhere(fem, [](const Vec3& X) { return X.x() == 0; }))
    fem.boundary_conditions().Fix(j);
  const double dt = 30 * fem.stable_dt_estimate();
  StepStatus status = StepStatus::Ok();
  VecX before;
  for (int k = 0; k < 200 && status.ok(); ++k) {
    before = fem.u();
    status = fem.Step(dt);
  }
  ASSERT_FALSE(status.ok()) << "30 times the stability estimate did not blow up";
  EXPECT_THAT(status.what, HasSubstr("inverted"));
  EXPECT_THAT(fem.failure_detail(),
              ::testing::MatchesRegex("SymplecticEuler: tet 10[0-9][0-9] \\(Gmsh element tag\\) is "
                                      "outside its law's domain.*"));
  EXPECT_GT(status.item, 1000);
  EXPECT_TRUE(fem.u() == before);
  EXPECT_TRUE(fem.u().allFinite());
}

TEST(FemOde, ConsistentMassAndCoupledCavitiesAreRefused) {
  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3::Ones(), {2, 2, 2}));
  FemParams params = AccurateParams(kCorotational, ImplicitSchemeKind::kBackwardEuler);
  try {
    FemSolid fem("cube", mesh, params, std::make_unique<RungeKutta4>());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("object 'cube': integrator 'RK4' steps the equations of "
                                    "motion as an ODE, which needs the lumped mass"));
  }
  params.lumped_mass = true;
  params.cavities.push_back({"lumen", GroupRegion{"xmin"}});
  FemSolid fem("cube", mesh, params, std::make_unique<RungeKutta4>());
  class Law final : public CavityLaw {
    bool EndVolume(double, double, double, double& v) override {
      v = 1;
      return true;
    }
  } law;
  try {
    fem.AttachCavityLaw("lumen", &law);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("cavity 'lumen' coupled to blood needs an implicit scheme"));
  }
}

std::string Scene(const std::string& object_keys) {
  return R"({"gipsi": 1, "meshes": {"m": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1],
    "cells": [1, 1, 1]}}, "objects": {"b": {"type": "FemSolid", "domain": "m", "dt": 0.001,
    "material": {"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.3})" +
         object_keys + "}}, \"schedule\": {\"end\": 0.01}}";
}

TEST(FemOde, SceneKeysThatWouldDoNothingAreRefusedWithTheirPath) {
  EXPECT_EQ(testing::SceneLoadError(Scene(R"(, "integrator": "RK4")")), "(no error)");
  EXPECT_THAT(testing::SceneLoadError(Scene(R"(, "integrator": "RK4", "newton": {})")),
              HasSubstr("objects.b.newton: has no effect with integrator 'RK4'"));
  EXPECT_THAT(testing::SceneLoadError(Scene(R"(, "integrator": "RK4", "mass": "consistent")")),
              HasSubstr("needs the lumped mass"));
  const std::string unknown = testing::SceneLoadError(Scene(R"(, "integrator": "RK5")"));
  EXPECT_THAT(unknown, HasSubstr("objects.b.integrator"));
  EXPECT_THAT(unknown, HasSubstr("RK4"));
  EXPECT_THAT(unknown, HasSubstr("Newmark"));
}

}  // namespace
}  // namespace gipsi
