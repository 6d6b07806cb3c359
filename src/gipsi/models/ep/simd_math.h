#pragma once
/// @file
/// Branch-free exp and log written so that GCC and Clang vectorise the loops that call them
/// (`#pragma omp simd` over nodes): only IEEE basic operations and 64-bit integer operations on
/// the bit patterns, no calls into libm. The same code runs in the vector body and in the scalar
/// remainder of a loop, so a cell's result does not depend on where a node range starts or ends
/// (libm's scalar and vector variants would differ in the last bits).
///
/// Accuracy (checked against std::exp/std::log in tests/models/ep/simd_math_test.cc):
///  - `FastExp`: relative error below 5e-16 (about 2 ulp) on [-708, 709]; arguments are
///    clamped to [range.lo, range.hi] first, so -inf gives exp(-708) ≈ 3e-308 and +inf gives
///    exp(709) ≈ 8e307 instead of 0 and inf.
///  - `FastLog`: absolute error below 3e-16 for x in [1e-300, 1e300] (relative error about 1 ulp
///    away from x = 1). x must be positive and normal; other values give finite garbage (the
///    models only take logarithms of concentration ratios).
///
/// Why the clamp bounds are run-time values: with -ftrapping-math (the default), GCC 12 threads
/// a clamp to a compile-time constant into a separate branch in which the rest of the function
/// is folded, and then refuses to if-convert (vectorise) the loop because the remaining
/// floating-point operations sit in a conditional block. The same happens to any constant
/// selected in the loop (`u < v_gate ? 1.0 : 0.0` followed by arithmetic). Values the compiler
/// cannot see (`Opaque`, `ExpRange::Load`: a volatile round trip per call of a kernel, outside
/// its loop) keep the loop body straight-line.

#include <bit>
#include <cstdint>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::simd {

/// `x`, read back through a volatile so that the optimiser cannot see the value (see the file
/// comment): for constants selected inside a vectorised loop, e.g. `open ? one : zero`. Call
/// outside the loop.
inline double Opaque(double x) {
  volatile double hidden = x;
  return hidden;
}

/// Clamp bounds of FastExp's argument. Trivially copyable.
struct ExpRange {
  double lo = -708.0;  ///< exp(lo) ≈ 3.3e-308, the smallest normal result
  double hi = 709.0;   ///< exp(hi) ≈ 8.2e307

  /// The default bounds, read through a volatile so that they are opaque to the optimiser
  /// (see the file comment). Call once outside the loop.
  static ExpRange Load() { return {Opaque(-708.0), Opaque(709.0)}; }
};

/// e^x for x clamped to [range.lo, range.hi]. Cody–Waite reduction x = n ln2 + r, |r| ≤ ln2/2,
/// a degree-12 Taylor polynomial for e^r (truncation error < 2e-16), and 2^n added to the
/// exponent field as an integer.
[[gnu::always_inline]] inline double FastExp(double x, const ExpRange& range) {
  x = x < range.lo ? range.lo : x;
  x = x > range.hi ? range.hi : x;
  constexpr double kLog2e = 1.4426950408889634074;
  constexpr double kLn2Hi = 6.93147180369123816490e-01;  // ln 2, high 32 bits (n * kLn2Hi exact)
  constexpr double kLn2Lo = 1.90821492927058770002e-10;  // ln 2 - kLn2Hi
  constexpr double kShift = 0x1.8p52;  // adding it rounds to an integer kept in the low bits
  const double t = x * kLog2e + kShift;
  const double n = t - kShift;
  const double r = (x - n * kLn2Hi) - n * kLn2Lo;
  double p = 1.0 / 479001600.0;  // 1/12!
  p = p * r + 1.0 / 39916800.0;
  p = p * r + 1.0 / 3628800.0;
  p = p * r + 1.0 / 362880.0;
  p = p * r + 1.0 / 40320.0;
  p = p * r + 1.0 / 5040.0;
  p = p * r + 1.0 / 720.0;
  p = p * r + 1.0 / 120.0;
  p = p * r + 1.0 / 24.0;
  p = p * r + 1.0 / 6.0;
  p = p * r + 0.5;
  p = p * r + 1.0;
  p = p * r + 1.0;
  // The low 12 bits of t's mantissa hold n (two's complement); shifted into the exponent field
  // they add n to p's exponent. |n| ≤ 1023 and p in [0.7, 1.5] keep the result normal.
  const std::uint64_t scale = std::bit_cast<std::uint64_t>(t) << 52;
  return std::bit_cast<double>(std::bit_cast<std::uint64_t>(p) + scale);
}

/// Natural logarithm of a positive normal x. x = 2^k m with m in [√½, √2) found with integer
/// operations only (no comparison), then log m = 2 atanh(s), s = (m − 1)/(m + 1), |s| ≤ 0.172,
/// by its odd series to s^21 (truncation error < 3e-17).
[[gnu::always_inline]] inline double FastLog(double x) {
  constexpr std::uint64_t kSqrtHalfBits = 0x3fe6a09e667f3bcdULL;  // bits of √½
  constexpr std::uint64_t kOneBits = 0x3ff0000000000000ULL;
  constexpr std::uint64_t kMantissa = 0x000fffffffffffffULL;
  constexpr std::uint64_t kMagicBits = 0x4330000000000000ULL;  // 2^52
  // Adding (1 − √½)'s mantissa offset carries into the exponent field exactly when x's mantissa
  // is at least √½'s, i.e. when m would reach √2 without the carry.
  const std::uint64_t u = std::bit_cast<std::uint64_t>(x) + (kOneBits - kSqrtHalfBits);
  const double biased_k = std::bit_cast<double>((u >> 52) | kMagicBits) - 0x1p52;
  const double k = biased_k - 1023.0;
  const double m = std::bit_cast<double>((u & kMantissa) + kSqrtHalfBits);
  const double s = (m - 1.0) / (m + 1.0);
  const double s2 = s * s;
  double p = 1.0 / 21.0;
  p = p * s2 + 1.0 / 19.0;
  p = p * s2 + 1.0 / 17.0;
  p = p * s2 + 1.0 / 15.0;
  p = p * s2 + 1.0 / 13.0;
  p = p * s2 + 1.0 / 11.0;
  p = p * s2 + 1.0 / 9.0;
  p = p * s2 + 1.0 / 7.0;
  p = p * s2 + 1.0 / 5.0;
  p = p * s2 + 1.0 / 3.0;
  const double log_m = 2.0 * s + 2.0 * s * s2 * p;
  constexpr double kLn2Hi = 6.93147180369123816490e-01;
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  return k * kLn2Hi + (log_m + k * kLn2Lo);
}

}  // namespace gipsi::simd
GIPSI_EXPORT_END
