#include "gipsi/numerics/ode.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace gipsi {
namespace {

/// Harmonic oscillator q'' = −ω² q as a mechanical system x = [q; v].
struct Oscillator {
  double omega = 2.0;
  Index ode_size() const { return 2; }
  Index ode_num_positions() const { return 1; }
  void CalcDerivative(double, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const {
    xdot[0] = x[1];
    xdot[1] = -omega * omega * x[0];
  }
  double Energy(const VecX& x) const { return 0.5 * (x[1] * x[1] + omega * omega * x[0] * x[0]); }
};
static_assert(OdeSystem<Oscillator>);

/// |x(T) − exact| after integrating from q=1, v=0 with `steps` steps.
double ErrorAtEnd(OdeIntegrator& integrator, int steps, double end = 1.0) {
  Oscillator osc;
  VecX x(2);
  x << 1.0, 0.0;
  integrator.Prepare(2);
  const double dt = end / steps;
  for (int k = 0; k < steps; ++k) integrator.Step(OdeView(osc), k * dt, dt, x);
  VecX exact(2);
  exact << std::cos(osc.omega * end), -osc.omega * std::sin(osc.omega * end);
  return (x - exact).norm();
}

/// Observed order from errors at dt and dt/2 over a sequence of refinements (last pair).
double ObservedOrder(OdeIntegrator& integrator) {
  const double e1 = ErrorAtEnd(integrator, 400);
  const double e2 = ErrorAtEnd(integrator, 800);
  return std::log2(e1 / e2);
}

// The asymptotic regime is reached at these step counts (ω·dt ≤ 0.005); a first-order method
// shows 1 ± 0.05, RK4 shows 4 ± 0.1 before round-off matters (errors ~1e-13).
TEST(ExplicitEuler, ConvergesAtFirstOrder) {
  ExplicitEuler integrator;
  EXPECT_NEAR(ObservedOrder(integrator), 1.0, 0.05);
}

TEST(SymplecticEuler, ConvergesAtFirstOrder) {
  SymplecticEuler integrator;
  EXPECT_NEAR(ObservedOrder(integrator), 1.0, 0.05);
}

TEST(RungeKutta4, ConvergesAtFourthOrder) {
  RungeKutta4 integrator;
  const double e1 = ErrorAtEnd(integrator, 25);
  const double e2 = ErrorAtEnd(integrator, 50);
  EXPECT_NEAR(std::log2(e1 / e2), 4.0, 0.1);
}

TEST(SymplecticEuler, KeepsEnergyBoundedOverManyPeriods) {
  // Symplectic Euler conserves a modified energy, so the true energy oscillates with amplitude
  // O(ω dt) but does not drift: after 1000 periods it stays in the band it had in the first.
  Oscillator osc;
  SymplecticEuler integrator;
  integrator.Prepare(2);
  VecX x(2);
  x << 1.0, 0.0;
  const double e0 = osc.Energy(x);
  const double period = 2 * std::numbers::pi / osc.omega;
  const int per_period = 100;
  const double dt = period / per_period;
  double first_band = 0, last_band = 0;
  const int periods = 1000;
  for (int k = 0; k < periods * per_period; ++k) {
    integrator.Step(OdeView(osc), k * dt, dt, x);
    const double deviation = std::abs(osc.Energy(x) - e0) / e0;
    if (k < per_period) first_band = std::max(first_band, deviation);
    if (k >= (periods - 1) * per_period) last_band = std::max(last_band, deviation);
  }
  // The band is set by ω·dt ≈ 0.063: the relative deviation is at most ω·dt (first order).
  EXPECT_LT(first_band, osc.omega * dt);
  EXPECT_LT(last_band, 1.05 * first_band);
}

TEST(ExplicitEuler, GainsEnergyEveryStep) {
  // Contrast with the symplectic method: forward Euler multiplies the energy of an undamped
  // oscillator by exactly (1 + ω²dt²) per step.
  Oscillator osc;
  ExplicitEuler integrator;
  integrator.Prepare(2);
  VecX x(2);
  x << 1.0, 0.0;
  const double dt = 0.01;
  const double e0 = osc.Energy(x);
  for (int k = 0; k < 100; ++k) integrator.Step(OdeView(osc), k * dt, dt, x);
  const double expected = e0 * std::pow(1 + osc.omega * osc.omega * dt * dt, 100);
  EXPECT_NEAR(osc.Energy(x), expected, 1e-12 * expected);
}

TEST(RungeKutta4, IntegratesGeneralFirstOrderSystems) {
  // y' = −y has no position/velocity split; RK4 handles it (y(1) = e^{-1}).
  struct Decay {
    Index ode_size() const { return 1; }
    Index ode_num_positions() const { return 0; }
    void CalcDerivative(double, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const {
      xdot[0] = -x[0];
    }
  } decay;
  RungeKutta4 integrator;
  integrator.Prepare(1);
  VecX y = VecX::Ones(1);
  for (int k = 0; k < 100; ++k) integrator.Step(OdeView(decay), k * 0.01, 0.01, y);
  EXPECT_NEAR(y[0], std::exp(-1.0), 1e-10);
}

TEST(SymplecticEulerDeathTest, RejectsSystemsWithoutPositions) {
  struct Decay {
    Index ode_size() const { return 1; }
    Index ode_num_positions() const { return 0; }
    void CalcDerivative(double, Eigen::Ref<const VecX>, Eigen::Ref<VecX> xdot) const {
      xdot[0] = 0;
    }
  } decay;
  SymplecticEuler integrator;
  integrator.Prepare(1);
  VecX y = VecX::Ones(1);
  EXPECT_DEATH(integrator.Step(OdeView(decay), 0, 0.1, y), "mechanical system");
}

// --- BackwardEulerOde: implicit, through the same OdeSystem contract ---

TEST(BackwardEulerOde, ConvergesAtFirstOrder) {
  BackwardEulerOde integrator;
  EXPECT_NEAR(ObservedOrder(integrator), 1.0, 0.05);
}

TEST(BackwardEulerOde, DampsTheOscillatorByItsClosedFormFactorFarBeyondTheExplicitLimit) {
  // On x' = J x with J skew in the energy norm, backward Euler multiplies the energy by exactly
  // 1 / (1 + ω²Δt²) per step. At ωΔt = 10 (explicit Euler would multiply it by 101) three steps
  // leave 101⁻³. The Jacobian-vector products of a linear f are exact up to rounding
  // (√ε relative, ~1e-8) and Newton iterates until its update is below 1e-10 of the state, so
  // the factor holds to ~1e-9; 1e-7 leaves margin for three steps.
  Oscillator osc;
  BackwardEulerOde integrator;
  integrator.Prepare(2);
  VecX x(2);
  x << 1.0, 0.0;
  const double dt = 10 / osc.omega;
  const double e0 = osc.Energy(x);
  for (int k = 1; k <= 3; ++k) {
    ASSERT_TRUE(integrator.Step(OdeView(osc), (k - 1) * dt, dt, x)) << integrator.failure();
    const double expected = e0 * std::pow(1 + osc.omega * osc.omega * dt * dt, -k);
    EXPECT_NEAR(osc.Energy(x), expected, 1e-7 * expected) << "step " << k;
    EXPECT_LE(integrator.last_newton_iterations(), 3);
  }
}

TEST(BackwardEulerOde, FollowsItsRecurrenceOnAStiffNonMechanicalEquation) {
  // Prothero–Robinson y' = λ (y − cos t) − sin t with λ = −10⁴ and Δt = 0.01 (|λ|Δt = 100, a
  // hundred times the explicit limit): the exact solution is cos t, and backward Euler's
  // recurrence is y₊ = (y + Δt (−λ cos t₊ − sin t₊)) / (1 − λΔt), computed here directly.
  struct ProtheroRobinson {
    double lambda = -1e4;
    Index ode_size() const { return 1; }
    Index ode_num_positions() const { return 0; }
    void CalcDerivative(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const {
      xdot[0] = lambda * (x[0] - std::cos(t)) - std::sin(t);
    }
  } system;
  BackwardEulerOde integrator;
  integrator.Prepare(1);
  VecX y = VecX::Constant(1, 2.0);  // off the smooth solution: a fast transient first
  double expected = 2.0;
  const double dt = 0.01;
  for (int k = 0; k < 100; ++k) {
    const double t1 = (k + 1) * dt;
    ASSERT_TRUE(integrator.Step(OdeView(system), k * dt, dt, y)) << integrator.failure();
    expected =
        (expected + dt * (-system.lambda * std::cos(t1) - std::sin(t1))) / (1 - system.lambda * dt);
    EXPECT_NEAR(y[0], expected, 1e-9) << "step " << k;
  }
  // And it is on the smooth solution: |y − cos t| = O(Δt/|λ|) after the transient.
  EXPECT_NEAR(y[0], std::cos(1.0), 1e-5);
}

TEST(BackwardEulerOde, AFailedSolveLeavesTheStateAndSaysWhy) {
  // f is finite at the start but not beyond |x| > 1.5, where the predictor lands.
  struct Blowup {
    Index ode_size() const { return 1; }
    Index ode_num_positions() const { return 0; }
    void CalcDerivative(double, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const {
      xdot[0] = std::abs(x[0]) > 1.5 ? std::numeric_limits<double>::quiet_NaN() : 10.0;
    }
  } system;
  BackwardEulerOde integrator;
  integrator.Prepare(1);
  VecX y = VecX::Ones(1);
  EXPECT_FALSE(integrator.Step(OdeView(system), 0, 0.1, y));
  EXPECT_EQ(y[0], 1.0);
  EXPECT_NE(integrator.failure().find("not finite"), std::string::npos) << integrator.failure();
}

}  // namespace
}  // namespace gipsi
