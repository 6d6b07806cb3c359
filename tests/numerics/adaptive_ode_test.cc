#include "gipsi/numerics/adaptive_ode.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace gipsi {
namespace {

using Outcome = AdaptiveOdeResult::Outcome;

/// x' = x cos t, x(0) = 1: x(t) = exp(sin t) (smooth, non-autonomous, non-polynomial).
struct ExpSin {
  Index ode_size() const { return 1; }
  Index ode_num_positions() const { return 0; }
  void CalcDerivative(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const {
    xdot[0] = x[0] * std::cos(t);
  }
  static double Exact(double t) { return std::exp(std::sin(t)); }
};

/// x' = p t^(p−1): x(t) = t^p for x(0) = 0.
struct Power {
  int p = 4;
  Index ode_size() const { return 1; }
  Index ode_num_positions() const { return 0; }
  void CalcDerivative(double t, Eigen::Ref<const VecX>, Eigen::Ref<VecX> xdot) const {
    xdot[0] = p * std::pow(t, p - 1);
  }
};

/// Harmonic oscillator [q, v]' = [v, −q]: q = cos t from q(0) = 1, v(0) = 0.
struct Harmonic {
  Index ode_size() const { return 2; }
  Index ode_num_positions() const { return 0; }
  void CalcDerivative(double, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const {
    xdot[0] = x[1];
    xdot[1] = -x[0];
  }
};

/// Event i: g_i(t, x) = c_i·x[0] + d_i + e_i·(t − t0)² (enough for the tests below).
struct QuadraticEvents final : EventFunctions {
  VecX c, d, e;
  double t0 = 0;
  int num_events() const override { return static_cast<int>(c.size()); }
  void Calc(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> g) const override {
    for (int i = 0; i < num_events(); ++i) g[i] = c[i] * x[0] + d[i] + e[i] * (t - t0) * (t - t0);
  }
};

/// Options that make every step exactly `h` (tolerance never binding).
AdaptiveOdeOptions FixedStep(double h) {
  AdaptiveOdeOptions options;
  options.relative_tolerance = 1e6;
  options.absolute_tolerance = 1e6;
  options.max_step = h;
  options.initial_step = h;
  return options;
}

double ExpSinErrorFixed(int steps, double end = 2.0) {
  ExpSin system;
  AdaptiveOde ode;
  ode.Prepare(1, 0, FixedStep(end / steps));
  VecX x = VecX::Ones(1);
  double t = 0;
  const auto result = ode.Integrate(OdeView(system), t, end, x);
  EXPECT_EQ(result.outcome, Outcome::kReachedEnd);
  EXPECT_EQ(result.accepted, steps);
  EXPECT_EQ(t, end);
  return std::abs(x[0] - ExpSin::Exact(end));
}

// Dormand–Prince 5(4) propagates the fifth-order solution: halving a fixed step divides the
// global error by 2^5 = 32. At 20–40 steps on [0, 2] the errors (~1e-8–1e-10) are far above
// round-off and in the asymptotic regime: the observed order is 5 ± 0.3.
TEST(AdaptiveOde, FixedStepsConvergeAtFifthOrder) {
  const double e1 = ExpSinErrorFixed(20);
  const double e2 = ExpSinErrorFixed(40);
  EXPECT_NEAR(std::log2(e1 / e2), 5.0, 0.3) << e1 << " " << e2;
}

// A fifth-order method integrates x = t^5 exactly (its local error involves the sixth
// derivative), and the quartic dense output reproduces x = t^4 at every interior time, both to
// round-off (1e-14 relative).
TEST(AdaptiveOde, ExactForQuinticSolutionAndDenseOutputExactForQuartic) {
  for (int p : {4, 5}) {
    Power system{p};
    AdaptiveOde ode;
    ode.Prepare(1, 0, FixedStep(0.5));
    VecX x = VecX::Zero(1);
    double t = 0;
    ASSERT_EQ(ode.Integrate(OdeView(system), t, 2.0, x).outcome, Outcome::kReachedEnd);
    EXPECT_NEAR(x[0], std::pow(2.0, p), 1e-14 * std::pow(2.0, p)) << p;
    if (p == 4) {
      // The last step is [1.5, 2]; its dense output is the quartic interpolant.
      VecX y(1);
      for (double s : {1.5, 1.6, 1.75, 1.9, 2.0}) {
        ode.Interpolate(s, y);
        EXPECT_NEAR(y[0], std::pow(s, 4), 1e-13) << s;
      }
    }
  }
}

// Dense output error: with fixed steps h the worst interpolation error inside the steps is
// O(h^5) (the fourth-order continuous extension's local error, plus the fifth-order global
// error of the step ends). Measured over the last step at 10 and 20 steps: order 5 ± 0.5.
TEST(AdaptiveOde, DenseOutputIsFourthOrderContinuous) {
  auto worst = [](int steps) {
    ExpSin system;
    AdaptiveOde ode;
    const double end = 2.0;
    ode.Prepare(1, 0, FixedStep(end / steps));
    VecX x = VecX::Ones(1), y(1);
    double t = 0;
    EXPECT_TRUE(ode.Integrate(OdeView(system), t, end, x).ok());
    double error = 0;
    for (int k = 0; k <= 20; ++k) {
      const double s = ode.step_begin() + (ode.step_end() - ode.step_begin()) * k / 20.0;
      ode.Interpolate(s, y);
      error = std::max(error, std::abs(y[0] - ExpSin::Exact(s)));
    }
    return error;
  };
  const double e1 = worst(10), e2 = worst(20);
  EXPECT_NEAR(std::log2(e1 / e2), 5.0, 0.5) << e1 << " " << e2;
}

// With error control, the global error follows the tolerance: at rtol = atol = 1e-6, 1e-8,
// 1e-10 the error at t = 10 stays below 10·tol (the local-to-global factor of this problem is
// O(1)) and falls by at least 10× per 100× tighter tolerance.
TEST(AdaptiveOde, ErrorFollowsTolerance) {
  double previous = 1;
  for (double tol : {1e-6, 1e-8, 1e-10}) {
    ExpSin system;
    AdaptiveOde ode;
    AdaptiveOdeOptions options;
    options.relative_tolerance = tol;
    options.absolute_tolerance = tol;
    ode.Prepare(1, 0, options);
    VecX x = VecX::Ones(1);
    double t = 0;
    const auto result = ode.Integrate(OdeView(system), t, 10.0, x);
    ASSERT_EQ(result.outcome, Outcome::kReachedEnd);
    const double error = std::abs(x[0] - ExpSin::Exact(10.0));
    EXPECT_LT(error, 10 * tol) << tol;
    EXPECT_LT(error, previous / 10) << tol;
    previous = error;
  }
}

// The oscillator's q = cos t crosses zero downward at π/2 and upward at 3π/2. With
// g0 = −q (upward crossing = q falling through 0), the event is located to the requested
// 1e-12 s plus the solution's own error (rtol 1e-12 → ~1e-12): within 1e-11 of π/2.
// Restarting from the event, g1 = q finds 3π/2.
TEST(AdaptiveOde, LocatesKnownCrossingTimes) {
  Harmonic system;
  QuadraticEvents events;
  events.c = VecX::Zero(1);
  events.d = VecX::Zero(1);
  events.e = VecX::Zero(1);
  events.c[0] = -1;
  AdaptiveOde ode;
  AdaptiveOdeOptions options;
  options.relative_tolerance = 1e-12;
  options.absolute_tolerance = 1e-14;
  options.event_tolerance = 1e-12;
  ode.Prepare(2, 1, options);
  VecX x(2);
  x << 1, 0;
  double t = 0;
  auto result = ode.Integrate(OdeView(system), t, 10.0, x, &events);
  ASSERT_EQ(result.outcome, Outcome::kEvent);
  EXPECT_EQ(result.event, 0);
  EXPECT_NEAR(t, std::numbers::pi / 2, 1e-11);
  EXPECT_GE(t, std::numbers::pi / 2 - 1e-11);  // reported on the positive side of g
  EXPECT_LT(std::abs(x[0]), 1e-11);
  // The state at the event is the dense output there: q = cos t to the tolerance.
  EXPECT_NEAR(x[1], -std::sin(t), 1e-10);

  events.c[0] = 1;  // now q rising through 0
  result = ode.Integrate(OdeView(system), t, 10.0, x, &events);
  ASSERT_EQ(result.outcome, Outcome::kEvent);
  EXPECT_NEAR(t, 1.5 * std::numbers::pi, 1e-11);
}

// x = exp(sin t) crosses 2 upward at t = asin(ln 2) (g = x − 2). Located within 1e-9 at the default
// 1e-10 event tolerance and rtol 1e-10.
TEST(AdaptiveOde, LocatesLevelCrossingOfNonlinearSolution) {
  ExpSin system;
  QuadraticEvents events;
  events.c = VecX::Ones(1);
  events.d = VecX::Constant(1, -2.0);
  events.e = VecX::Zero(1);
  AdaptiveOde ode;
  AdaptiveOdeOptions options;
  options.relative_tolerance = 1e-10;
  options.absolute_tolerance = 1e-12;
  ode.Prepare(1, 1, options);
  VecX x = VecX::Ones(1);
  double t = 0;
  const auto result = ode.Integrate(OdeView(system), t, 3.0, x, &events);
  ASSERT_EQ(result.outcome, Outcome::kEvent);
  EXPECT_NEAR(t, std::asin(std::log(2.0)), 1e-9);
}

// Of two functions crossing in the same step, the earlier crossing is reported.
TEST(AdaptiveOde, ReportsTheEarliestOfSeveralEvents) {
  Power system{1};  // x = t
  QuadraticEvents events;
  events.c = VecX::Ones(2);
  events.d = VecX(2);
  events.d << -0.7, -0.4;  // x = 0.7 and x = 0.4
  events.e = VecX::Zero(2);
  AdaptiveOde ode;
  ode.Prepare(1, 2, FixedStep(1.0));
  VecX x = VecX::Zero(1);
  double t = 0;
  const auto result = ode.Integrate(OdeView(system), t, 2.0, x, &events);
  ASSERT_EQ(result.outcome, Outcome::kEvent);
  EXPECT_EQ(result.event, 1);
  EXPECT_NEAR(t, 0.4, 1e-10);
}

// A function that goes positive and back inside one step has no sign change at the step's
// ends; the interior samples catch it. g = 0.01 − (t − 2.5)² is positive on (2.4, 2.6) and
// the single step [0, 5] samples θ = 0.5 (t = 2.5). With one sample per step it is missed —
// the documented limit of sampling.
TEST(AdaptiveOde, InteriorSamplesCatchADoubleCrossingInOneStep) {
  Power system{1};
  QuadraticEvents events;
  events.c = VecX::Zero(1);
  events.d = VecX::Constant(1, 0.01);
  events.e = VecX::Constant(1, -1.0);
  events.t0 = 2.5;
  for (int samples : {4, 1}) {
    AdaptiveOde ode;
    AdaptiveOdeOptions options = FixedStep(5.0);
    options.event_samples = samples;
    ode.Prepare(1, 1, options);
    VecX x = VecX::Zero(1);
    double t = 0;
    const auto result = ode.Integrate(OdeView(system), t, 5.0, x, &events);
    if (samples == 4) {
      ASSERT_EQ(result.outcome, Outcome::kEvent);
      EXPECT_NEAR(t, 2.4, 1e-9);
    } else {
      EXPECT_EQ(result.outcome, Outcome::kReachedEnd);
    }
  }
}

TEST(AdaptiveOde, FirstPositiveReportsPendingEvents) {
  QuadraticEvents events;
  events.c = VecX::Ones(2);
  events.d = VecX(2);
  events.d << -2, -0.5;
  events.e = VecX::Zero(2);
  AdaptiveOde ode;
  ode.Prepare(1, 2, AdaptiveOdeOptions{});
  EXPECT_EQ(ode.FirstPositive(events, 0, VecX::Constant(1, 1.0)), 1);
  EXPECT_EQ(ode.FirstPositive(events, 0, VecX::Constant(1, 0.1)), -1);
}

/// x' = x², x(0) = 1: x = 1/(1 − t) blows up at t = 1.
struct BlowUp {
  Index ode_size() const { return 1; }
  Index ode_num_positions() const { return 0; }
  void CalcDerivative(double, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const {
    xdot[0] = x[0] * x[0];
  }
};

// A singular problem ends with a failure outcome (not a hang, an exception or a run to t_end):
// the controller shrinks the step as x explodes until it falls below the minimum, near t = 1
// (an explicit method lags the exact blow-up slightly, so t may pass 1 by a little), with x
// the last accepted, finite (and huge) state.
TEST(AdaptiveOde, FailsCleanlyAtASingularity) {
  BlowUp system;
  AdaptiveOde ode;
  ode.Prepare(1, 0, AdaptiveOdeOptions{});
  VecX x = VecX::Ones(1);
  double t = 0;
  const auto result = ode.Integrate(OdeView(system), t, 2.0, x);
  EXPECT_FALSE(result.ok());
  EXPECT_NEAR(t, 1.0, 1e-3);
  EXPECT_TRUE(std::isfinite(x[0]));
  EXPECT_GT(x[0], 1e6);
}

}  // namespace
}  // namespace gipsi
