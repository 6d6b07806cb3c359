#pragma once
/// @file
/// Four doubles as one value, for kernels written once and compiled twice: plainly (the compiler
/// splits each operation into SSE2 pairs) and inside a function with
/// `__attribute__((target("avx")))` (single 256-bit instructions), selected at run time by
/// ActiveSimdKernels (simd.h). Every lane is one IEEE operation in the written order and the
/// AVX target has no FMA, so both copies give the same bits.
///
/// Rules that keep this portable between GCC and Clang: pass V4d and structs of them by
/// reference only (a by-value V4d changes the ABI between the two copies, which Clang refuses),
/// and put shared code in GIPSI_SIMD_INLINE functions so each copy inlines its own. Internal to
/// the numerical kernels; not part of the API.

#include <cstring>

namespace gipsi::simd {

typedef double V4d __attribute__((vector_size(32)));
typedef long long V4i __attribute__((vector_size(32)));

#define GIPSI_SIMD_INLINE inline __attribute__((always_inline))

GIPSI_SIMD_INLINE void Load(V4d& v, const double* p) { std::memcpy(&v, p, sizeof v); }
GIPSI_SIMD_INLINE void Store(double* p, const V4d& v) { std::memcpy(p, &v, sizeof v); }

/// Σ_{i ∈ [begin, end)} a[i] b[i] in four lanes (the tail added to lanes 0–2), then
/// (lane 0 + lane 1) + (lane 2 + lane 3): the same bits in either copy.
GIPSI_SIMD_INLINE double Dot(const double* __restrict a, const double* __restrict b, int begin,
                             int end) {
  V4d sum = {0.0, 0.0, 0.0, 0.0};
  int i = begin;
  for (; i + 4 <= end; i += 4) {
    V4d ai, bi;
    Load(ai, a + i);
    Load(bi, b + i);
    sum += ai * bi;
  }
  double chain[4];
  Store(chain, sum);
  for (int c = 0; i < end; ++i, ++c) chain[c] += a[i] * b[i];
  return (chain[0] + chain[1]) + (chain[2] + chain[3]);
}

}  // namespace gipsi::simd
