// SolveIncreasingRoot: roots of increasing scalar functions, and its refusals.

#include "gipsi/numerics/bracketed_root.h"

#include <cmath>

#include <gtest/gtest.h>

namespace gipsi {
namespace {

TEST(SolveIncreasingRoot, FindsTheRootOfACubicFromEitherSide) {
  // h(x) = x³ + x − 10 has its one real root at x = 2 (8 + 2 − 10); starting 3 units away on
  // either side with a unit first step, the bracket doubles out and Illinois closes it to the
  // tolerance (|h| ≤ 1e-12, so |x − 2| ≤ 1e-12 / h'(2) = 1e-12 / 13).
  auto h = [](double x, double& out) {
    out = x * x * x + x - 10;
    return true;
  };
  auto unit = [](double h0) { return h0 > 0 ? -1.0 : 1.0; };
  for (double guess : {-1.0, 5.0}) {
    double root = 0, slope = 0;
    ASSERT_TRUE(SolveIncreasingRoot(h, guess, unit, 1e-12, root, &slope)) << guess;
    EXPECT_NEAR(root, 2.0, 1e-12 / 13) << guess;
    EXPECT_GT(slope, 0);
  }
}

TEST(SolveIncreasingRoot, RefusesWithoutARootOrWhenTheFunctionFails) {
  double root = 0;
  auto unit = [](double h0) { return h0 > 0 ? -1.0 : 1.0; };
  // 1 + eˣ > 1 everywhere: 80 doublings of the step never change its sign.
  auto positive = [](double x, double& out) {
    out = 1 + std::exp(x);
    return true;
  };
  EXPECT_FALSE(SolveIncreasingRoot(positive, 0.0, unit, 1e-12, root));
  // A function that cannot be evaluated beyond x = 0.5 (e.g. a law outside its domain).
  auto partial = [](double x, double& out) {
    out = x - 2;
    return x < 0.5;
  };
  EXPECT_FALSE(SolveIncreasingRoot(partial, 0.0, unit, 1e-12, root));
}

}  // namespace
}  // namespace gipsi
