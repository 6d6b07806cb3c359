#include "gipsi/numerics/sparse/cg_kernels.h"

#include <cmath>
#include <cstring>
#include <limits>

#include <gtest/gtest.h>

#include "gipsi/numerics/simd.h"
#include "numerics/sparse/sparse_test_util.h"

namespace gipsi {
namespace {

using testing::RandomVector;
using testing::SameBits;

struct CgVectors {
  VecX d, w, x, r, z, p, s;
  explicit CgVectors(Index n)
      : d(RandomVector(n, 1).cwiseAbs()),
        w(RandomVector(n, 2) * 1e3),
        x(RandomVector(n, 3)),
        r(RandomVector(n, 4) * 1e-4),
        z(RandomVector(n, 5)),
        p(RandomVector(n, 6) * 1e2),
        s(RandomVector(n, 7)) {}
};

// The update sweep does what its contract says (against a plain loop, to round-off), and the
// AVX and generic versions give the same bits, for ranges of every length mod 4 and any start.
TEST(CgKernels, UpdateSweepFollowsTheRecurrencesWithTheSameBitsOnEveryKernel) {
  const Index n = 1003;
  const double alpha = 0.37, beta = 1.9;
  for (const auto& range : {std::pair{0, 1003}, std::pair{1, 1000}, std::pair{5, 7}}) {
    const int begin = range.first, end = range.second;  // (lambdas below use them)
    CgVectors plain(n), active(n), generic(n);
    double rr = 0, rz = 0;
    for (int i = begin; i < end; ++i) {
      plain.p[i] = plain.z[i] + beta * plain.p[i];
      plain.s[i] = plain.w[i] + beta * plain.s[i];
      plain.x[i] += alpha * plain.p[i];
      plain.r[i] -= alpha * plain.s[i];
      plain.z[i] = plain.d[i] * plain.r[i];
      rr += plain.r[i] * plain.r[i];
      rz += plain.r[i] * plain.z[i];
    }
    auto run = [&](CgVectors& v) {
      return CgUpdateRows(alpha, beta, v.d.data(), v.w.data(), v.x.data(), v.r.data(), v.z.data(),
                          v.p.data(), v.s.data(), begin, end);
    };
    const CgUpdateSums a = run(active);
    const SimdKernels before = LimitSimdKernels(SimdKernels::kGeneric);
    const CgUpdateSums g = run(generic);
    LimitSimdKernels(before);
    // Element-wise updates: the same operations as the plain loop, so the same bits.
    for (VecX CgVectors::*v :
         {&CgVectors::x, &CgVectors::r, &CgVectors::z, &CgVectors::p, &CgVectors::s}) {
      EXPECT_TRUE(SameBits(plain.*v, active.*v)) << begin << ".." << end;
      EXPECT_TRUE(SameBits(plain.*v, generic.*v)) << begin << ".." << end;
    }
    // The sums in four chains: another order than the plain loop's, the same on both kernels.
    EXPECT_EQ(std::memcmp(&a.rr, &g.rr, sizeof a.rr), 0);
    EXPECT_EQ(std::memcmp(&a.rz, &g.rz, sizeof a.rz), 0);
    EXPECT_NEAR(a.rr, rr, 1e-15 * rr * (end - begin));
    EXPECT_NEAR(a.rz, rz, 1e-15 * std::abs(rz) * (end - begin) + 1e-300);
  }
}

TEST(CgKernels, DotIsTheSameOnEveryKernel) {
  const VecX a = RandomVector(777, 8), b = RandomVector(777, 9) * 1e7;
  for (const auto& [begin, end] : {std::pair{0, 777}, std::pair{3, 774}, std::pair{2, 3}}) {
    const double active = DotRows(a.data(), b.data(), begin, end);
    const SimdKernels before = LimitSimdKernels(SimdKernels::kGeneric);
    const double generic = DotRows(a.data(), b.data(), begin, end);
    LimitSimdKernels(before);
    EXPECT_EQ(std::memcmp(&active, &generic, sizeof active), 0);
    const double plain = a.segment(begin, end - begin).dot(b.segment(begin, end - begin));
    EXPECT_NEAR(active, plain, 1e-14 * b.norm() * a.norm());
  }
}

// A NaN or an infinity anywhere, in the four-lane part or the tail, is found by both kernels;
// large finite values (whose squares would overflow) and negative zeros are finite.
TEST(CgKernels, AllFiniteFindsEveryNonFiniteValue) {
  VecX v = RandomVector(103, 10) * 1e300;
  v[7] = -0.0;
  for (const SimdKernels kernels : {SimdKernels::kAvx, SimdKernels::kGeneric}) {
    const SimdKernels before = LimitSimdKernels(kernels);
    EXPECT_TRUE(AllFiniteValues(v.data(), v.size()));
    EXPECT_TRUE(AllFiniteValues(v.data(), 0));
    for (const Index at : {Index{0}, Index{50}, Index{101}, Index{102}})
      for (const double bad :
           {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
            -std::numeric_limits<double>::infinity()}) {
        VecX w = v;
        w[at] = bad;
        EXPECT_FALSE(AllFiniteValues(w.data(), w.size())) << "at " << at << ": " << bad;
        EXPECT_TRUE(AllFiniteValues(w.data(), at)) << "the values before " << at;
      }
    LimitSimdKernels(before);
  }
}

}  // namespace
}  // namespace gipsi
