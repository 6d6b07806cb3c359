#include <cmath>
#include <cstring>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/core/kernel.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/fem/fem_solid.h"
#include "models/fem/fem_test_util.h"

namespace gipsi {
namespace {

using testing::AccurateParams;
using ::testing::HasSubstr;
using testing::VerticesWhere;

constexpr const char* kLinear = R"({"law": "Linear", "youngs_modulus": 1e5, "poisson_ratio": 0.3})";

/// A clamped 1 m × 0.1 m × 0.1 m beam, released with a bending-shaped velocity.
std::unique_ptr<FemSolid> VibratingBeam(const std::string& law, ImplicitSchemeKind scheme,
                                        int cells = 8) {
  auto mesh =
      std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3(1, 0.1, 0.1), {cells, 1, 1}));
  auto fem = std::make_unique<FemSolid>("beam", mesh, AccurateParams(law, scheme));
  for (Index j : VerticesWhere(*fem, [](const Vec3& X) { return X.x() == 0; }))
    fem->boundary_conditions().Fix(j);
  Points v = Points::Zero(3, mesh->num_nodes());
  for (Index i = 0; i < mesh->num_nodes(); ++i) v(2, i) = 0.5 * std::pow(mesh->nodes(0, i), 2);
  fem->WriteField(fem->FindField("velocity"), v);
  return fem;
}

double Energy(const FemSolid& fem) { return fem.KineticEnergy() + fem.StrainEnergy(); }

TEST(FemDynamics, NewmarkAverageAccelerationConservesEnergyOfALinearBeam) {
  // For a linear system the average-acceleration Newmark scheme conserves ½vᵀMv + ½xᵀKx
  // exactly; what remains is the Newton/linear-solve tolerance (1e-12 relative).
  auto fem = VibratingBeam(kLinear, ImplicitSchemeKind::kNewmark);
  const double e0 = Energy(*fem);
  ASSERT_GT(e0, 0);
  double worst = 0;
  for (int k = 0; k < 200; ++k) {
    ASSERT_TRUE(fem->Step(0.02).ok()) << fem->failure_detail();
    worst = std::max(worst, std::abs(Energy(*fem) - e0) / e0);
  }
  EXPECT_LT(worst, 1e-9);
}

TEST(FemDynamics, NewmarkKeepsTheEnergyOfALargeRotationCorotationalBeamBounded) {
  // Nonlinear (corotational) case: no exact conservation, but no drift beyond the scheme's
  // second-order error over many periods.
  auto fem =
      VibratingBeam(R"({"law": "Corotational", "youngs_modulus": 1e5, "poisson_ratio": 0.3})",
                    ImplicitSchemeKind::kNewmark);
  Points v = Points::Zero(3, fem->num_nodes());
  for (Index i = 0; i < fem->num_nodes(); ++i)
    v(2, i) = 3.0 * std::pow(fem->domain().nodes(0, i), 2);
  fem->WriteField(fem->FindField("velocity"), v);  // tip speed 3 m/s: large rotations
  const double e0 = Energy(*fem);
  double worst = 0;
  for (int k = 0; k < 200; ++k) {
    ASSERT_TRUE(fem->Step(0.01).ok()) << fem->failure_detail();
    worst = std::max(worst, std::abs(Energy(*fem) - e0) / e0);
  }
  EXPECT_LT(worst, 0.02);
}

TEST(FemDynamics, BackwardEulerDissipatesEnergyMonotonically) {
  auto fem = VibratingBeam(kLinear, ImplicitSchemeKind::kBackwardEuler);
  double previous = Energy(*fem);
  for (int k = 0; k < 50; ++k) {
    ASSERT_TRUE(fem->Step(0.02).ok());
    const double e = Energy(*fem);
    EXPECT_LT(e, previous);
    previous = e;
  }
}

TEST(FemDynamics, SchemesConvergeAtTheirOrder) {
  // One corotational tet with three nodes clamped and the fourth swinging at large amplitude:
  // a smooth nonlinear oscillator (period ≈ 1.3 s) whose modes are all resolved by the steps
  // used, so the observed order is the schemes' own. Reference: Newmark with 4096 steps.
  auto position = [](ImplicitSchemeKind scheme, int steps) {
    auto mesh = std::make_shared<Mesh>();
    mesh->nodes.resize(3, 4);
    mesh->nodes << 0, 1, 0, 0.2, 0, 0, 1, 0.2, 0, 0, 0, 1;
    mesh->tets.resize(4, 1);
    mesh->tets << 0, 1, 2, 3;
    auto fem = std::make_unique<FemSolid>(
        "tet", mesh,
        AccurateParams(R"({"law": "Corotational", "youngs_modulus": 1e3, "poisson_ratio": 0.3})",
                       scheme));
    for (Index j = 0; j < 4; ++j)
      if (fem->boundary().vertex_to_node[static_cast<std::size_t>(j)] != 3)
        fem->boundary_conditions().Fix(j);
    Points v = Points::Zero(3, 4);
    v.col(3) = Vec3(1.5, 0.5, -0.3);
    fem->WriteField(fem->FindField("velocity"), v);
    for (int k = 0; k < steps; ++k) EXPECT_TRUE(fem->Step(1.0 / steps).ok());
    return Vec3(fem->x().segment<3>(9));
  };
  const Vec3 reference = position(ImplicitSchemeKind::kNewmark, 4096);
  struct Case {
    ImplicitSchemeKind scheme;
    double order;
  };
  for (const Case& c :
       {Case{ImplicitSchemeKind::kBackwardEuler, 1}, Case{ImplicitSchemeKind::kBdf2, 2},
        Case{ImplicitSchemeKind::kNewmark, 2}}) {
    SCOPED_TRACE(std::string(ToString(c.scheme)));
    const double e1 = (position(c.scheme, 64) - reference).norm();
    const double e2 = (position(c.scheme, 128) - reference).norm();
    const double e3 = (position(c.scheme, 256) - reference).norm();
    const double order = 0.5 * (std::log2(e1 / e2) + std::log2(e2 / e3));
    std::printf("%s: errors %.3g %.3g %.3g, observed order %.2f\n",
                std::string(ToString(c.scheme)).c_str(), e1, e2, e3, order);
    // Asymptotic orders are reached to within ±0.15 at these steps (ω·dt ≤ 0.08).
    EXPECT_NEAR(order, c.order, 0.15);
  }
}

TEST(FemDynamics, RepeatedRunsGiveIdenticalBits) {
  auto run = [] {
    auto fem =
        VibratingBeam(R"({"law": "NeoHookean", "youngs_modulus": 1e5, "poisson_ratio": 0.3})",
                      ImplicitSchemeKind::kBdf2);
    for (int k = 0; k < 10; ++k) EXPECT_TRUE(fem->Step(0.01).ok());
    return VecX(fem->x());
  };
  const VecX a = run(), b = run();
  EXPECT_EQ(0,
            std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())));
}

TEST(FemDynamics, CrushingANeoHookeanBlockFailsWithADiagnosticAndKeepsTheState) {
  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3::Ones(), {2, 2, 2}));
  FemParams params =
      AccurateParams(R"({"law": "NeoHookean", "youngs_modulus": 1e4, "poisson_ratio": 0.3})",
                     ImplicitSchemeKind::kStatic);
  params.max_bisections = 0;  // fail at once: the first iterate already inverts elements
  FemSolid fem("block", mesh, params);
  for (Index j : VerticesWhere(fem, [](const Vec3& X) { return X.z() == 0; }))
    fem.boundary_conditions().Fix(j);
  // Pushing the top 1.5 m down through the bottom of a 1 m block has no admissible solution.
  for (Index j : VerticesWhere(fem, [](const Vec3& X) { return X.z() == 1; }))
    fem.boundary_conditions().PrescribeDisplacement(j, Vec3(0, 0, -1.5), 4);
  const StepStatus status = fem.Step(1.0);
  EXPECT_FALSE(status.ok());
  EXPECT_THAT(fem.failure_detail(), HasSubstr("element"));
  EXPECT_TRUE(fem.x().allFinite());
}

TEST(FemDynamics, PredictorsReachTheSameStatesInFewerIterations) {
  // A predictor only moves Newton's first iterate: every run solves each step to a relative
  // residual of 1e-10, so after 20 steps the states agree to a tiny fraction of the motion
  // (bound 1e-9 of it; measured 4e-13), and the smooth swing needs fewer iterations with a
  // constant-velocity start and fewer still with a constant-acceleration one.
  const char* law = R"({"law": "Corotational", "youngs_modulus": 1e5, "poisson_ratio": 0.3})";
  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3(1, 0.1, 0.1), {8, 1, 1}));
  using P = FemParams::Predictor;
  auto run = [&](P predictor, std::int64_t& iterations) {
    FemParams params = AccurateParams(law, ImplicitSchemeKind::kBackwardEuler);
    params.predictor = predictor;
    FemSolid fem("beam", mesh, params);
    for (Index j : VerticesWhere(fem, [](const Vec3& X) { return X.x() == 0; }))
      fem.boundary_conditions().Fix(j);
    Points v = Points::Zero(3, mesh->num_nodes());
    for (Index i = 0; i < mesh->num_nodes(); ++i) v(2, i) = 0.5 * std::pow(mesh->nodes(0, i), 2);
    fem.WriteField(fem.FindField("velocity"), v);
    for (int k = 0; k < 20; ++k) EXPECT_TRUE(fem.Step(0.01).ok()) << fem.failure_detail();
    iterations = fem.profile().newton_iterations;
    return VecX(fem.x());
  };
  std::int64_t plain = 0, velocity = 0, acceleration = 0;
  const VecX a = run(P::kNone, plain), b = run(P::kConstantVelocity, velocity),
             c = run(P::kConstantAcceleration, acceleration);
  const VecX rest = Eigen::Map<const VecX>(mesh->nodes.data(), a.size());
  const double motion = (a - rest).lpNorm<Eigen::Infinity>();
  ASSERT_GT(motion, 0.05);
  EXPECT_LT((a - b).lpNorm<Eigen::Infinity>(), 1e-9 * motion);
  EXPECT_LT((a - c).lpNorm<Eigen::Infinity>(), 1e-9 * motion);
  EXPECT_LT(velocity, plain);
  EXPECT_LT(acceleration, velocity) << "none " << plain << ", velocity " << velocity;
}

TEST(FemSolid, TheConvergenceScaleIncludesPressureLoads) {
  // Newton's tolerance is relative to max(‖r(d₀)‖, force scale); the force scale must count
  // pressure loads (a heart's only loads), else a step starting near equilibrium is solved to
  // a vanishing absolute residual. Expected: the nodal forces of p on the top face of a unit
  // block at rest, Σ_faces p·A/3 on each vertex (top vertices are all free).
  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3::Ones(), {2, 2, 2}));
  FemSolid fem("block", mesh,
               AccurateParams(R"({"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.3})",
                              ImplicitSchemeKind::kStatic));
  for (Index j : VerticesWhere(fem, [](const Vec3& X) { return X.z() == 0; }))
    fem.boundary_conditions().Fix(j);
  const double p = 100;
  VecX expected = VecX::Zero(3 * mesh->num_nodes());
  const BoundarySurface& b = fem.boundary();
  for (Index f : testing::FacesWhere(fem, [](const Vec3& X) { return X.z() == 1; })) {
    fem.boundary_conditions().SetPressure(f, p);
    Vec3 x[3];
    Index node[3];
    for (int k = 0; k < 3; ++k) {
      node[k] = b.vertex_to_node[static_cast<std::size_t>(b.triangles(k, f))];
      x[k] = mesh->nodes.col(node[k]);
    }
    const double area = 0.5 * (x[1] - x[0]).cross(x[2] - x[0]).norm();
    for (int k = 0; k < 3; ++k) expected[3 * node[k] + 2] -= p * area / 3;  // pushes down
  }
  ASSERT_TRUE(fem.Step(1.0).ok()) << fem.failure_detail();
  EXPECT_NEAR(fem.load_scale(), expected.norm(), 1e-12 * expected.norm());
}

TEST(FemSolidScene, BadInputGivesClearErrors) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  auto load = [&](const std::string& object) {
    const std::string text = R"({"gipsi": 1, "meshes": {"box": {"generate": "box", "min": [0,0,0],
      "max": [1,1,1], "cells": [1,1,1]}}, "objects": {"tissue": )" +
                             object + R"(}, "schedule": {"end": 0.1, "dt": 0.1}})";
    try {
      (void)LoadSceneFromString(text, "scene.json", ".", registry);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(load(R"({"type": "FemSolid", "domain": "box"})"),
              HasSubstr("objects.tissue: missing required key 'material'"));
  EXPECT_THAT(load(R"({"type": "FemSolid", "domain": "box", "material": {"law": "Guccione",
      "C": 2000, "bf": 8, "bt": 2, "bfs": 4, "bulk_modulus": 1e5}})"),
              HasSubstr("fibres"));
  EXPECT_THAT(load(R"({"type": "FemSolid", "domain": "box", "integrator": "Euler",
      "material": {"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.3}})"),
              HasSubstr("BackwardEuler"));
  EXPECT_THAT(load(R"({"type": "FemSolid", "domain": "box", "material": {"law": "Hooke"}})"),
              HasSubstr("objects.tissue.material"));
  EXPECT_THAT(load(R"({"type": "FemSolid", "domain": "box", "newmark": {"beta": 0.1},
      "material": {"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.3}})"),
              HasSubstr("objects.tissue.newmark"));
  EXPECT_THAT(load(R"({"type": "FemSolid", "domain": "box", "predictor": "linear",
      "material": {"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.3}})"),
              HasSubstr("objects.tissue.predictor"));
  EXPECT_EQ(load(R"({"type": "FemSolid", "domain": "box", "integrator": "Static",
      "material": {"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.3}})"),
            "no error");
}

}  // namespace
}  // namespace gipsi
