#include "gipsi/models/ep/simd_math.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace gipsi::simd {
namespace {

TEST(FastExp, MatchesStdExpToTwoUlpsOverTheNormalRange) {
  const ExpRange range = ExpRange::Load();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> wide(-708.0, 709.0), narrow(-1.0, 1.0);
  double worst = 0;
  for (int i = 0; i < 200000; ++i) {
    for (double x : {wide(rng), narrow(rng)}) {
      const double want = std::exp(x);
      worst = std::max(worst, std::abs(FastExp(x, range) - want) / want);
    }
  }
  EXPECT_LT(worst, 5e-16);
  EXPECT_EQ(FastExp(0.0, range), 1.0);
}

TEST(FastExp, ClampsArgumentsOutsideTheRange) {
  const ExpRange range = ExpRange::Load();
  EXPECT_EQ(FastExp(-1e300, range), FastExp(-708.0, range));
  EXPECT_EQ(FastExp(-HUGE_VAL, range), FastExp(-708.0, range));
  EXPECT_GT(FastExp(-HUGE_VAL, range), 0.0);
  EXPECT_EQ(FastExp(1e300, range), FastExp(709.0, range));
  EXPECT_TRUE(std::isfinite(FastExp(HUGE_VAL, range)));
}

TEST(FastLog, MatchesStdLogOverPositiveNormalNumbers) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> exponent(-690.0, 690.0), near_one(0.5, 2.0);
  double worst = 0;
  for (int i = 0; i < 200000; ++i) {
    for (double x : {std::exp(exponent(rng)), near_one(rng)}) {
      const double want = std::log(x);
      worst = std::max(worst, std::abs(FastLog(x) - want) / std::max(1.0, std::abs(want)));
    }
  }
  EXPECT_LT(worst, 3e-16);
  EXPECT_EQ(FastLog(1.0), 0.0);
  EXPECT_DOUBLE_EQ(FastLog(2.0), std::log(2.0));
  EXPECT_DOUBLE_EQ(FastLog(1.0 + 1e-12), std::log(1.0 + 1e-12));
}

TEST(FastExpAndLog, GiveTheSameBitsInAVectorisedLoopAndOneAtATime) {
  std::vector<double> x(1001), vec(x.size()), one(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = -50.0 + 0.1 * static_cast<double>(i);
  const ExpRange range = ExpRange::Load();
  const double* __restrict in = x.data();
  double* __restrict out = vec.data();
#pragma omp simd
  for (std::size_t i = 0; i < x.size(); ++i)
    out[i] = FastExp(in[i], range) + FastLog(2.0 + in[i] * in[i]);
  for (std::size_t i = 0; i < x.size(); ++i)
    one[i] = FastExp(x[i], range) + FastLog(2.0 + x[i] * x[i]);
  for (std::size_t i = 0; i < x.size(); ++i) ASSERT_EQ(vec[i], one[i]) << i;
}

}  // namespace
}  // namespace gipsi::simd
