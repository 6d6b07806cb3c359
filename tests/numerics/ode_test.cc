#include "gipsi/numerics/ode.h"

#include <cmath>
#include <numbers>
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
double ErrorAtEnd(ExplicitIntegrator& integrator, int steps, double end = 1.0) {
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
double ObservedOrder(ExplicitIntegrator& integrator) {
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

}  // namespace
}  // namespace gipsi
