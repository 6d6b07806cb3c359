#include "gipsi/models/mass_spring/mass_spring.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/generators.h"

namespace gipsi {
namespace {

std::shared_ptr<const Mesh> Box(int cells = 2) {
  return std::make_shared<const Mesh>(
      MakeTetBox(Vec3::Zero(), Vec3(0.1, 0.1, 0.1), {cells, cells, cells}));
}

std::unique_ptr<OdeIntegrator> Make(const std::string& name) {
  if (name == "ExplicitEuler") return std::make_unique<ExplicitEuler>();
  if (name == "RK4") return std::make_unique<RungeKutta4>();
  return std::make_unique<SymplecticEuler>();
}

class MassSpringMomentum : public ::testing::TestWithParam<std::string> {};

TEST_P(MassSpringMomentum, ConservesLinearMomentumWithoutGravityOrDamping) {
  MassSpringParams params;
  params.gravity.setZero();
  params.stiffness = 50;
  MassSpring object("cube", Box(), params, Make(GetParam()));
  // Random velocities and a random distortion: springs push and pull internally only.
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixXd v(3, object.num_nodes()), q = object.domain().nodes;
  for (Index i = 0; i < v.size(); ++i) {
    v.data()[i] = 0.1 * u(rng);
    q.data()[i] += 0.005 * u(rng);
  }
  object.WriteField(object.FindField("velocity"), v);
  object.WriteField(object.FindField("position"), q);
  const Vec3 p0 = object.Momentum();
  const double scale = object.masses().sum() * 0.1;  // |m v| scale
  for (int k = 0; k < 2000; ++k) ASSERT_TRUE(object.Step(1e-4).ok());
  // Each step adds spring forces that cancel pairwise: momentum changes only by round-off.
  EXPECT_LT((object.Momentum() - p0).norm(), 1e-12 * scale);
  EXPECT_GT(object.KineticEnergy(), 0);
}

INSTANTIATE_TEST_SUITE_P(AllIntegrators, MassSpringMomentum,
                         ::testing::Values("ExplicitEuler", "SymplecticEuler", "RK4"));

/// One spring (rest length 0.1 m, stiffness 20 N/m) hanging `mass` from a fixed node of 1 kg,
/// damped and run for 20 s: the damped transient (rate ≥ c/2m) is far below round-off by then.
std::unique_ptr<MassSpring> SettledHangingSpring(double mass, double damping,
                                                 std::shared_ptr<const SpringLaw> law) {
  Points nodes(3, 2);
  nodes.col(0) = Vec3(0, 0, 0);
  nodes.col(1) = Vec3(0, 0, -0.1);
  Eigen::Matrix2Xi springs(2, 1);
  springs << 0, 1;
  VecX masses(2);
  masses << 1.0, mass;
  MassSpringParams params;
  params.stiffness = 20;
  params.damping = damping;
  params.law = std::move(law);
  auto object = std::make_unique<MassSpring>("spring", nodes, springs, masses, params,
                                             std::make_unique<SymplecticEuler>());
  object->boundary_conditions().Fix(0);
  for (int k = 0; k < 20000; ++k) EXPECT_TRUE(object->Step(1e-3).ok());
  return object;
}

double Sag(const MassSpring& object) { return -(object.domain_positions()(2, 1) + 0.1); }

TEST(MassSpring, SingleSpringSagsByMgOverK) {
  // Equilibrium extension m g / k; the decay rate c/2m = 5/s leaves e^-100 of the transient, and
  // the discrete scheme's equilibrium is exact, so only round-off remains.
  auto object = SettledHangingSpring(0.05, 0.5, nullptr);
  EXPECT_NEAR(Sag(*object), 0.05 * 9.81 / 20, 1e-12);
  // The fixed node stays put.
  EXPECT_EQ(object->domain_positions().col(0), object->domain().nodes.col(0));
  Eigen::MatrixXd reaction(3, 2);
  object->ReadField(object->FindField("reaction_force"), reaction);
  // The support carries the spring tension m g plus the weight of the fixed node itself.
  EXPECT_NEAR(reaction(2, 0), (0.05 + 1.0) * 9.81, 1e-10);
}

TEST(MassSpring, LumpedMassEqualsDensityTimesVolume) {
  MassSpringParams params;
  params.density = 1200;
  MassSpring object("cube", Box(3), params, std::make_unique<SymplecticEuler>());
  EXPECT_NEAR(object.masses().sum(), 1200 * 1e-3, 1e-12);
}

TEST(MassSpring, SheetMassUsesThickness) {
  auto sheet = std::make_shared<const Mesh>(
      MakeTriangleSheet(Vec3::Zero(), Vec3(0.2, 0, 0), Vec3(0, 0.1, 0), {4, 2}));
  MassSpringParams params;
  params.density = 1000;
  params.thickness = 0.002;
  MassSpring object("sheet", sheet, params, std::make_unique<SymplecticEuler>());
  EXPECT_NEAR(object.masses().sum(), 1000 * 0.002 * 0.02, 1e-12);
  // 4x2 quads: 15 nodes, 5·2 + 4·3 + 8 diagonals = 30 unique edges.
  EXPECT_EQ(object.num_springs(), 30);
}

TEST(MassSpring, SymplecticEulerKeepsEnergyBoundedWithoutDamping) {
  MassSpringParams params;
  params.gravity.setZero();
  MassSpring object("cube", Box(), params, std::make_unique<SymplecticEuler>());
  Eigen::MatrixXd q = object.domain().nodes;
  q.row(0) *= 1.05;  // stretch 5 % along x and let it vibrate
  object.WriteField(object.FindField("position"), q);
  const double e0 = object.PotentialEnergy() + object.KineticEnergy();
  double worst = 0;
  for (int k = 0; k < 20000; ++k) {
    ASSERT_TRUE(object.Step(2e-4).ok());
    worst = std::max(worst, std::abs(object.PotentialEnergy() + object.KineticEnergy() - e0));
  }
  // dt is well inside the stability limit; the symplectic energy error stays a few percent.
  EXPECT_LT(2e-4, 0.5 * object.stable_dt_estimate());
  EXPECT_LT(worst, 0.05 * e0);
}

TEST(MassSpring, PrescribedVelocityMovesVertexAtThatVelocity) {
  MassSpring object("cube", Box(), MassSpringParams{}, std::make_unique<RungeKutta4>());
  object.boundary_conditions().PrescribeVelocity(0, Vec3(0.01, 0, 0));
  const int node = object.boundary().vertex_to_node[0];
  const Vec3 start = object.domain_positions().col(node);
  for (int k = 0; k < 100; ++k) ASSERT_TRUE(object.Step(1e-4).ok());
  EXPECT_NEAR((object.domain_positions().col(node) - start).x(), 0.01 * 100 * 1e-4, 1e-15);
}

TEST(MassSpring, ReportsDivergenceForTooLargeStep) {
  MassSpringParams params;
  params.stiffness = 1e4;
  MassSpring object("cube", Box(), params, std::make_unique<ExplicitEuler>());
  StepStatus status;
  int k = 0;
  for (; k < 10000 && status.ok(); ++k) status = object.Step(0.05);
  EXPECT_EQ(status.code, StepStatus::Code::kDiverged);
  EXPECT_LT(k, 10000);
  // The state it reports on is not silently NaN: the failing step is flagged, not hidden.
  EXPECT_NE(std::string(status.what), "");
}

TEST(MassSpring, RejectsCoincidentNodes) {
  Points nodes = Points::Zero(3, 2);
  Eigen::Matrix2Xi springs(2, 1);
  springs << 0, 1;
  EXPECT_THROW(MassSpring("bad", nodes, springs, VecX::Ones(2), MassSpringParams{},
                          std::make_unique<SymplecticEuler>()),
               InputError);
}

TEST(MassSpring, PressureOnClosedSurfaceAddsNoNetForce) {
  // A uniform pressure on a closed surface integrates to zero net force.
  MassSpringParams params;
  params.gravity.setZero();
  MassSpring object("cube", Box(), params, std::make_unique<SymplecticEuler>());
  for (Index f = 0; f < object.boundary().num_triangles(); ++f)
    object.boundary_conditions().SetPressure(f, 1000);
  for (int k = 0; k < 50; ++k) ASSERT_TRUE(object.Step(1e-4).ok());
  EXPECT_LT(object.Momentum().norm(), 1e-14);
  // ... but it compresses the cube: every boundary vertex moved inward (towards the centre).
  const Vec3 centre(0.05, 0.05, 0.05);
  const auto& v2n = object.boundary().vertex_to_node;
  int inward = 0;
  for (int node : v2n)
    inward += (object.domain_positions().col(node) - centre).norm() <
              (object.domain().nodes.col(node) - centre).norm();
  EXPECT_EQ(inward, static_cast<int>(v2n.size()));
}

TEST(SpringLaw, ExponentialMatchesHookeForSmallStrainAndStiffens) {
  HookeSpring hooke;
  ExponentialSpring exponential(10);
  const double k = 50, rest = 0.02;
  // Small strain (1e-6): tensions agree to O(b ε) relative.
  const double small = rest * (1 + 1e-6);
  EXPECT_NEAR(exponential.Tension(small, rest, k) / hooke.Tension(small, rest, k), 1, 1e-5);
  // At 20 % strain the exponential law is (e^{2} − 1)/2 ≈ 3.19 times stiffer in tension.
  const double big = rest * 1.2;
  EXPECT_NEAR(exponential.Tension(big, rest, k) / hooke.Tension(big, rest, k),
              std::expm1(2.0) / 2.0, 1e-12);
}

TEST(SpringLaw, TensionIsTheDerivativeOfEnergy) {
  ExponentialSpring exponential(7);
  const double k = 30, rest = 0.05;
  for (double length : {0.03, 0.05, 0.055, 0.08}) {
    const double h = 1e-7;
    const double numeric =
        (exponential.Energy(length + h, rest, k) - exponential.Energy(length - h, rest, k)) /
        (2 * h);
    EXPECT_NEAR(exponential.Tension(length, rest, k), numeric, 1e-6);
    const double tangent =
        (exponential.Tension(length + h, rest, k) - exponential.Tension(length - h, rest, k)) /
        (2 * h);
    EXPECT_NEAR(exponential.TangentStiffness(length, rest, k), tangent, 1e-4 * tangent);
  }
  EXPECT_EQ(exponential.Energy(rest, rest, k), 0.0);
}

TEST(MassSpring, ExponentialSpringSagsLessThanHookeUnderTheSameLoad) {
  const double hooke = Sag(*SettledHangingSpring(0.2, 1, std::make_shared<HookeSpring>()));
  const double exponential =
      Sag(*SettledHangingSpring(0.2, 1, std::make_shared<ExponentialSpring>(5)));
  EXPECT_NEAR(hooke, 0.2 * 9.81 / 20, 1e-12);
  // Exponential equilibrium: (k L0 / b)(e^{b ε} − 1) = m g  →  ε = ln(1 + m g b / (k L0)) / b.
  const double strain = std::log1p(0.2 * 9.81 * 5 / (20 * 0.1)) / 5;
  EXPECT_NEAR(exponential, strain * 0.1, 1e-12);
  EXPECT_LT(exponential, hooke);
}

/// A chain of `n` springs (rest length 0.1 m, 100 N/m) hanging from a fixed top node, node
/// masses 10 g, released unstretched.
std::unique_ptr<MassSpring> HangingChain(int n, double drag,
                                         std::unique_ptr<OdeIntegrator> integrator) {
  Points nodes(3, n + 1);
  for (int i = 0; i <= n; ++i) nodes.col(i) = Vec3(0, 0, -0.1 * i);
  Eigen::Matrix2Xi springs(2, n);
  for (int i = 0; i < n; ++i) springs.col(i) << i, i + 1;
  MassSpringParams params;
  params.stiffness = 100;
  params.drag = drag;
  auto chain = std::make_unique<MassSpring>("chain", nodes, springs, VecX::Constant(n + 1, 0.01),
                                            params, std::move(integrator));
  chain->boundary_conditions().Fix(0);
  return chain;
}

TEST(MassSpring, BackwardEulerSettlesAHangingChainAtItsStaticSagBeyondTheExplicitLimit) {
  // Spring i carries the n − i nodes below it: elongation m g (n − i) / k. Backward Euler's
  // fixed point is f = 0, the static equilibrium; its slowest mode (ω ≈ 15/s) loses a factor
  // 0.8 per step at Δt = 0.05 s, so after 400 steps only Newton's tolerance (1e-10 of the
  // state) remains.
  const int n = 10;
  auto chain = HangingChain(n, 0.5, std::make_unique<BackwardEulerOde>());
  const double dt = 0.05;
  ASSERT_GT(dt, 5 * chain->stable_dt_estimate());
  for (int k = 0; k < 400; ++k) ASSERT_TRUE(chain->Step(dt).ok()) << k << chain->failure_detail();
  double z = 0;
  for (int i = 0; i < n; ++i) {
    z -= 0.1 + 0.01 * 9.81 * (n - i) / 100;
    EXPECT_NEAR(chain->domain_positions()(2, i + 1), z, 1e-9) << "node " << i + 1;
  }
  // The explicit default (symplectic Euler) diverges at the same step.
  auto explicit_chain = HangingChain(n, 0.5, std::make_unique<SymplecticEuler>());
  bool diverged = false;
  for (int k = 0; k < 400 && !diverged; ++k) diverged = !explicit_chain->Step(dt).ok();
  EXPECT_TRUE(diverged);
}

TEST(MassSpring, BackwardEulerConvergesAtFirstOrderToAReferenceSolution) {
  // Three springs released from rest for 0.2 s, undamped. Reference: RK4 at Δt = 1e-5 s
  // (ω_max Δt ≈ 0.002, error ~1e-13). Backward Euler at ω_max Δt ≈ 0.09 and 0.045 is in its
  // asymptotic regime: the error halves with the step (order 1 ± 0.1).
  auto run = [](std::unique_ptr<OdeIntegrator> integrator, double dt) {
    auto chain = HangingChain(3, 0, std::move(integrator));
    const auto steps = std::lround(0.2 / dt);
    for (long k = 0; k < steps; ++k) EXPECT_TRUE(chain->Step(dt).ok()) << chain->failure_detail();
    return Points(chain->domain_positions());
  };
  const Points reference = run(std::make_unique<RungeKutta4>(), 1e-5);
  const double e1 = (run(std::make_unique<BackwardEulerOde>(), 5e-4) - reference).norm();
  const double e2 = (run(std::make_unique<BackwardEulerOde>(), 2.5e-4) - reference).norm();
  EXPECT_NEAR(std::log2(e1 / e2), 1.0, 0.1) << e1 << " " << e2;
  EXPECT_LT(e2, 1e-3);  // against a motion of ~3 cm amplitude
}

}  // namespace
}  // namespace gipsi
