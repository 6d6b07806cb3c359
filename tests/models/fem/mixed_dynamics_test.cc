// MixedSolid dynamics: the consistent P2 mass (exact integrals on straight and curved tets), the
// time schemes on a free fall (their exact velocities), and a damped motion that settles on the
// quasi-static answer. The bitwise resume of a dynamic scene is in tests/core/checkpoint_test.cc.

#include <cmath>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include <fmt/format.h>

#include "gipsi/geometry/generators.h"
#include "gipsi/io/mesh_io.h"
#include "gipsi/models/fem/mixed_solid.h"
#include "io/io_test_util.h"
#include "models/fem/fem_test_util.h"

namespace gipsi {
namespace {

using testing::Law;
using testing::VerticesWhere;

constexpr double kDensity = 1100;
const char* kSoft = R"({"law": "NeoHookean", "youngs_modulus": 1e4, "poisson_ratio": 0.45})";

MixedSolidParams DynamicParams(ImplicitSchemeKind scheme, bool incompressible) {
  MixedSolidParams p;
  p.material = Law(kSoft);
  p.incompressible = incompressible;
  p.scheme = scheme;
  p.density = kDensity;
  p.newton.tolerance = 1e-11;
  p.newton.max_iterations = 40;
  return p;
}

// M_ab = ∫ ρ N_a N_b dV is exact for the product of two P2 fields, so for the interpolants of
// 1, x and x² (all in P2) the mass gives ρ ∫ 1, ρ ∫ x and ρ ∫ x³ over a box: to round-off.
TEST(MixedDynamics, TheConsistentMassIntegratesQuadraticFieldsExactly) {
  const Vec3 size(0.03, 0.01, 0.02);
  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), size, {3, 1, 2}));
  MixedSolid solid("box", mesh, DynamicParams(ImplicitSchemeKind::kBackwardEuler, false));
  const Points& rest = solid.quadratic_mesh().rest;
  const Index n = rest.cols();
  Points one = Points::Zero(3, n), x = Points::Zero(3, n), x2 = Points::Zero(3, n);
  one.row(0).setOnes();
  x.row(0) = rest.row(0);
  x2.row(0) = rest.row(0).array().square().matrix();
  const double volume = size.prod();
  const double lx = size.x();
  auto inner = [&](const Points& a, const Points& b) {
    return (a.array() * solid.ApplyMass(b).array()).sum();
  };
  EXPECT_NEAR(inner(one, one), kDensity * volume, 1e-13 * kDensity * volume);
  EXPECT_NEAR(inner(one, x), kDensity * volume * lx / 2, 1e-13 * kDensity * volume * lx);
  EXPECT_NEAR(inner(x, x2), kDensity * volume * lx * lx * lx / 4,
              1e-13 * kDensity * volume * lx * lx * lx);
}

// On curved (isoparametric) tets det J varies: the mass rule integrates N_a N_b det J exactly,
// so the total mass is ρ times the curved octant's volume, which is the thick sphere's
// (π/6)(R³ − r³) to the P2 geometry's error (1e-4 allowed, as for the rest volume in
// curved_mixed_test.cc), while straight edges miss 1 % or more.
TEST(MixedDynamics, TheMassOfCurvedTetsIsTheCurvedVolumes) {
  const double inner_radius = 0.01, outer_radius = 0.02;
  const double exact =
      kDensity * M_PI / 6 * (std::pow(outer_radius, 3) - std::pow(inner_radius, 3));
  for (const bool curved : {true, false}) {
    Mesh mesh = ReadMesh(test::MeshData("thick_sphere_octant_0.7.msh"));
    mesh.Transform(inner_radius, Vec3::Zero());
    if (!curved) {
      mesh.edge_node_ends.resize(2, 0);
      mesh.edge_nodes.resize(3, 0);
    }
    MixedSolid solid("octant", std::make_shared<const Mesh>(std::move(mesh)),
                     DynamicParams(ImplicitSchemeKind::kBackwardEuler, true));
    Points one = Points::Zero(3, solid.quadratic_mesh().num_nodes());
    one.row(0).setOnes();
    const double mass = solid.ApplyMass(one).row(0).sum();
    if (curved)
      EXPECT_NEAR(mass / exact, 1, 1e-4);
    else
      EXPECT_LT(mass / exact, 0.99);
  }
}

// A free body under gravity moves rigidly, with no stress and no pressure, and each scheme's
// velocity is exact for a constant acceleration: v_n = g t_n (backward Euler: v += g Δt;
// BDF2: its first, backward-Euler step is exact in v, and BDF2 is exact for linear v).
// Backward Euler's displacement is Δt² g n(n + 1)/2 (x += Δt v_{n+1}). The kinetic energy is
// ½ m |g t|². To the Newton tolerance.
TEST(MixedDynamics, AFreeFallHasEachSchemesExactVelocities) {
  const Vec3 g(0, 0, -9.81);
  const double dt = 0.01;
  const int steps = 8;
  for (const ImplicitSchemeKind scheme :
       {ImplicitSchemeKind::kBackwardEuler, ImplicitSchemeKind::kBdf2,
        ImplicitSchemeKind::kNewmark}) {
    SCOPED_TRACE(std::string(ToString(scheme)));
    MixedSolidParams params = DynamicParams(scheme, false);
    params.gravity = g;
    const Vec3 size(0.02, 0.01, 0.01);
    auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), size, {2, 1, 1}));
    MixedSolid solid("box", mesh, params);
    for (int n = 1; n <= steps; ++n) ASSERT_TRUE(solid.Step(dt).ok()) << solid.failure_detail();
    const double t = steps * dt;
    const Points v = solid.NodeVelocities();
    const Points u = solid.NodeDisplacements();
    for (Index a = 0; a < v.cols(); ++a) {
      EXPECT_LT((v.col(a) - g * t).norm(), 1e-9 * g.norm() * t) << "node " << a;
      if (scheme == ImplicitSchemeKind::kBackwardEuler) {
        EXPECT_LT((u.col(a) - g * dt * dt * steps * (steps + 1) / 2).norm(),
                  1e-9 * g.norm() * t * t)
            << "node " << a;
      }
      // Newmark's average acceleration is exact for a constant one, from a₀ = g (its initial
      // acceleration, solved with the mass and the pressure).
      if (scheme == ImplicitSchemeKind::kNewmark) {
        EXPECT_LT((u.col(a) - 0.5 * g * t * t).norm(), 1e-9 * g.norm() * t * t) << "node " << a;
      }
    }
    EXPECT_LT(solid.Pressures().lpNorm<Eigen::Infinity>(), 1e-6);
    Eigen::MatrixXd kinetic(1, 1);
    solid.ReadField(solid.FindField("kinetic_energy"), kinetic);
    const double mass = kDensity * size.prod();
    EXPECT_NEAR(kinetic(0, 0), 0.5 * mass * (g * t).squaredNorm(),
                1e-8 * mass * (g * t).squaredNorm());
  }
}

// A velocity written to a free body without loads moves it rigidly: x = v₀ t at every node,
// kinetic energy ½ m |v₀|² (the edge nodes take the mean of their ends' written velocities).
TEST(MixedDynamics, AWrittenVelocityMovesAFreeBodyRigidly) {
  const Vec3 v0(0.02, -0.01, 0.03);
  const Vec3 size(0.02, 0.01, 0.01);
  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), size, {2, 1, 1}));
  MixedSolid solid("box", mesh, DynamicParams(ImplicitSchemeKind::kBdf2, true));
  Eigen::MatrixXd v(3, mesh->num_nodes());
  v.colwise() = v0;
  solid.WriteField(solid.FindField("velocity"), v);
  const double dt = 0.01;
  const int steps = 6;
  for (int n = 0; n < steps; ++n) ASSERT_TRUE(solid.Step(dt).ok()) << solid.failure_detail();
  const Points u = solid.NodeDisplacements();
  for (Index a = 0; a < u.cols(); ++a)
    EXPECT_LT((u.col(a) - v0 * dt * steps).norm(), 1e-10 * v0.norm() * dt * steps) << a;
  Eigen::MatrixXd kinetic(1, 1);
  solid.ReadField(solid.FindField("kinetic_energy"), kinetic);
  const double mass = kDensity * size.prod();
  EXPECT_NEAR(kinetic(0, 0), 0.5 * mass * v0.squaredNorm(), 1e-9 * mass * v0.squaredNorm());
}

// A dynamic MixedSolid honours prescribed velocities: the driven face's vertices move at
// exactly that velocity with either scheme (each step's increment is the one that gives it),
// and read it back; a quasi-static one refuses them (mixed_solid_test.cc).
TEST(MixedDynamics, APrescribedVelocityDrivesItsVertices) {
  const Vec3 v0(0, 0, 0.05);
  const Vec3 size(0.01, 0.01, 0.02);
  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), size, {1, 1, 2}));
  for (const ImplicitSchemeKind scheme :
       {ImplicitSchemeKind::kBackwardEuler, ImplicitSchemeKind::kBdf2}) {
    SCOPED_TRACE(std::string(ToString(scheme)));
    MixedSolid solid("column", mesh, DynamicParams(scheme, true));
    const auto base = VerticesWhere(solid, [](const Vec3& x) { return x.z() < 1e-12; });
    for (Index j : base) solid.boundary_conditions().PrescribeVelocity(j, v0);
    const double dt = 0.005;
    const int steps = 8;
    for (int n = 0; n < steps; ++n)
      ASSERT_TRUE(solid.Step(dt).ok()) << "step " << n << ": " << solid.failure_detail();
    Eigen::MatrixXd velocity(3, solid.boundary().num_vertices());
    solid.ReadField(solid.FindField("boundary_velocity"), velocity);
    Eigen::MatrixXd displacement(3, solid.boundary().num_vertices());
    solid.ReadField(solid.FindField("boundary_displacement"), displacement);
    for (Index j : base) {
      EXPECT_LT((velocity.col(j) - v0).norm(), 1e-12 * v0.norm()) << j;
      EXPECT_LT((displacement.col(j) - v0 * dt * steps).norm(), 1e-12 * v0.norm() * dt * steps)
          << j;
    }
  }
}

// An incompressible column (2 × 1 × 1 cm, held at its base) released under its weight (BDF2, and
// Newmark from its initial acceleration), with
// mass-proportional damping α = 150/s, about critical for its lowest (bending) mode, ω ≈ 70/s
// (a 2 cm cantilever of E = 3μ): every mode then decays at least as e^(−45 t). After 0.8 s
// every node is where the quasi-static solve puts it, to 1e-6 of the largest displacement, at
// rest (measured 3e-13 and 0), and the volume has been held throughout (5e-6 measured). On the
// way the base's reaction balances the weight and the momentum change.
TEST(MixedDynamics, ADampedMotionSettlesOnTheQuasiStaticAnswer) {
  const Vec3 g(0, 0, -9.81);
  const Vec3 size(0.01, 0.01, 0.02);
  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), size, {1, 1, 2}));
  auto hold_base = [](MixedSolid& solid) {
    for (Index v : VerticesWhere(solid, [](const Vec3& x) { return x.z() < 1e-12; }))
      solid.boundary_conditions().Fix(v);
  };
  MixedSolidParams static_params = DynamicParams(ImplicitSchemeKind::kStatic, true);
  static_params.gravity = g;
  static_params.load_steps = 2;
  MixedSolid reference("static", mesh, static_params);
  hold_base(reference);
  ASSERT_TRUE(reference.Step(1).ok()) << reference.failure_detail();

  {
    MixedSolidParams params = DynamicParams(ImplicitSchemeKind::kBdf2, true);
    params.gravity = g;
    params.rayleigh_mass = 150;
    MixedSolid solid("dynamic", mesh, params);
    hold_base(solid);
    const double rest_volume = solid.CurrentVolume();
    double worst_volume = 0;
    const double weight = kDensity * size.prod() * g.norm();
    for (int n = 0; n < 160; ++n) {
      ASSERT_TRUE(solid.Step(0.005).ok()) << "step " << n << ": " << solid.failure_detail();
      worst_volume = std::max(worst_volume, std::abs(solid.CurrentVolume() / rest_volume - 1));
      if (n != 5) continue;
      // Mid-motion, the base carries the weight and the body's momentum change: Σ R_z =
      // Σ (M (a + α v))_z − m g_z (the internal forces sum to zero).
      Eigen::MatrixXd reaction(3, solid.boundary().num_vertices());
      solid.ReadField(solid.FindField("reaction_force"), reaction);
      const MixedSolid& s = solid;
      const Points a =
          Eigen::Map<const Points>(s.state().scheme.a().data(), 3, s.quadratic_mesh().num_nodes());
      const double momentum_change =
          s.ApplyMass(a + params.rayleigh_mass * s.NodeVelocities()).row(2).sum();
      ASSERT_GT(std::abs(momentum_change), 0.01 * weight);  // still moving
      EXPECT_NEAR(reaction.row(2).sum(), momentum_change + weight, 1e-8 * weight);
    }
    const Points expected = reference.NodeDisplacements();
    const double scale = expected.colwise().norm().maxCoeff();
    ASSERT_GT(scale, 1e-5);  // it did sag (about 0.1 mm)
    EXPECT_LT((solid.NodeDisplacements() - expected).colwise().norm().maxCoeff(), 1e-6 * scale);
    EXPECT_LT(solid.NodeVelocities().colwise().norm().maxCoeff(), 1e-6 * scale);
    // P1 pressure: J = 1 holds weakly; 1e-4 as for the inflated sphere (curved_mixed_test.cc).
    EXPECT_LT(worst_volume, 1e-4);
  }
}

// Newmark's average acceleration conserves the energy of a linear system, and that of a
// nonlinear one to O(Δt²): the same column, undamped, released from rest under its weight,
// swings with kinetic + strain energy − the weight's work (0 at rest) conserved to 1.3e-3 of
// the largest kinetic energy over 0.2 s with Δt = 2 ms, and 3.6e-4 with 1 ms (3.7 times less:
// O(Δt²), asserted above 3), where BDF2 loses all of it. Newmark starts from its initial
// acceleration (the mass and pressure solve), and the column's volume is held from the first
// step on.
double SwingEnergyDrift(ImplicitSchemeKind scheme, double dt) {
  const Vec3 g(0, 0, -9.81);
  const Vec3 size(0.01, 0.01, 0.02);
  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), size, {1, 1, 2}));
  MixedSolidParams params = DynamicParams(scheme, true);
  params.gravity = g;
  MixedSolid solid("swing", mesh, params);
  for (Index v : VerticesWhere(solid, [](const Vec3& x) { return x.z() < 1e-12; }))
    solid.boundary_conditions().Fix(v);
  Points gravity(3, solid.quadratic_mesh().num_nodes());
  gravity.colwise() = g;
  const Points weight = solid.ApplyMass(gravity);  // M g on every node
  const double rest_volume = solid.CurrentVolume();
  double worst_volume = 0, top_kinetic = 0, drift = 0;
  Eigen::MatrixXd kinetic(1, 1), strain(1, 1);
  const int steps = static_cast<int>(std::lround(0.2 / dt));
  for (int step = 0; step < steps; ++step) {
    EXPECT_TRUE(solid.Step(dt).ok()) << solid.failure_detail();
    solid.ReadField(solid.FindField("kinetic_energy"), kinetic);
    solid.ReadField(solid.FindField("strain_energy"), strain);
    const double work = (weight.array() * solid.NodeDisplacements().array()).sum();
    top_kinetic = std::max(top_kinetic, kinetic(0, 0));
    drift = std::max(drift, std::abs(kinetic(0, 0) + strain(0, 0) - work));
    worst_volume = std::max(worst_volume, std::abs(solid.CurrentVolume() / rest_volume - 1));
  }
  EXPECT_LT(worst_volume, 1e-4);
  fmt::print("[ info     ] {} at {} ms: energy drift {:.2e} of the largest kinetic energy\n",
             ToString(scheme), dt * 1e3, drift / top_kinetic);
  return drift / top_kinetic;
}

TEST(MixedDynamics, NewmarkSwingsWithoutLosingEnergy) {
  const double coarse = SwingEnergyDrift(ImplicitSchemeKind::kNewmark, 0.002);
  const double fine = SwingEnergyDrift(ImplicitSchemeKind::kNewmark, 0.001);
  const double bdf2 = SwingEnergyDrift(ImplicitSchemeKind::kBdf2, 0.002);
  EXPECT_LT(coarse, 5e-3);
  EXPECT_LT(fine, coarse / 3);  // O(Δt²)
  EXPECT_GT(bdf2, 0.5);
}

}  // namespace
}  // namespace gipsi
