#include "gipsi/numerics/sparse/cg_kernels.h"

#include "gipsi/numerics/simd.h"
#include "gipsi/numerics/simd_v4.h"

namespace gipsi {
namespace {

using simd::Load;
using simd::Store;
using V4 = simd::V4d;

GIPSI_SIMD_INLINE CgUpdateSums UpdateBody(double alpha, double beta, const double* __restrict d,
                                          const double* __restrict w, double* __restrict x,
                                          double* __restrict r, double* __restrict z,
                                          double* __restrict p, double* __restrict s, int begin,
                                          int end) {
  V4 rr = {0.0, 0.0, 0.0, 0.0}, rz = rr;
  const V4 a = {alpha, alpha, alpha, alpha}, b = {beta, beta, beta, beta};
  int i = begin;
  for (; i + 4 <= end; i += 4) {
    V4 pi, si, zi, wi, xi, ri, di;
    Load(pi, p + i);
    Load(si, s + i);
    Load(zi, z + i);
    Load(wi, w + i);
    Load(xi, x + i);
    Load(ri, r + i);
    Load(di, d + i);
    pi = zi + b * pi;
    si = wi + b * si;
    xi += a * pi;
    ri -= a * si;
    zi = di * ri;
    rr += ri * ri;
    rz += ri * zi;
    Store(p + i, pi);
    Store(s + i, si);
    Store(x + i, xi);
    Store(r + i, ri);
    Store(z + i, zi);
  }
  double chain_rr[4], chain_rz[4];
  Store(chain_rr, rr);
  Store(chain_rz, rz);
  for (int c = 0; i < end; ++i, ++c) {
    p[i] = z[i] + beta * p[i];
    s[i] = w[i] + beta * s[i];
    x[i] += alpha * p[i];
    r[i] -= alpha * s[i];
    z[i] = d[i] * r[i];
    chain_rr[c] += r[i] * r[i];
    chain_rz[c] += r[i] * z[i];
  }
  return {(chain_rr[0] + chain_rr[1]) + (chain_rr[2] + chain_rr[3]),
          (chain_rz[0] + chain_rz[1]) + (chain_rz[2] + chain_rz[3])};
}

// x · 0 is 0 for a finite x and NaN otherwise, so one sum of them is NaN iff a value is not
// finite (then its comparison with itself fails).
GIPSI_SIMD_INLINE bool AllFiniteBody(const double* __restrict values, std::ptrdiff_t n) {
  V4 sum = {0.0, 0.0, 0.0, 0.0};
  std::ptrdiff_t i = 0;
  for (; i + 4 <= n; i += 4) {
    V4 v;
    Load(v, values + i);
    sum += v * 0.0;
  }
  double lanes[4];
  Store(lanes, sum);
  double total = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
  for (; i < n; ++i) total += values[i] * 0.0;
  return total == total;
}

bool AllFiniteGeneric(const double* values, std::ptrdiff_t n) { return AllFiniteBody(values, n); }

CgUpdateSums UpdateGeneric(double alpha, double beta, const double* d, const double* w, double* x,
                           double* r, double* z, double* p, double* s, int begin, int end) {
  return UpdateBody(alpha, beta, d, w, x, r, z, p, s, begin, end);
}

double DotGeneric(const double* a, const double* b, int begin, int end) {
  return simd::Dot(a, b, begin, end);
}

#if defined(__x86_64__)
__attribute__((target("avx"))) CgUpdateSums UpdateAvx(double alpha, double beta, const double* d,
                                                      const double* w, double* x, double* r,
                                                      double* z, double* p, double* s, int begin,
                                                      int end) {
  return UpdateBody(alpha, beta, d, w, x, r, z, p, s, begin, end);
}

__attribute__((target("avx"))) bool AllFiniteAvx(const double* values, std::ptrdiff_t n) {
  return AllFiniteBody(values, n);
}

__attribute__((target("avx"))) double DotAvx(const double* a, const double* b, int begin, int end) {
  return simd::Dot(a, b, begin, end);
}
#endif

}  // namespace

CgUpdateSums CgUpdateRows(double alpha, double beta, const double* d, const double* w, double* x,
                          double* r, double* z, double* p, double* s, int begin, int end) {
#if defined(__x86_64__)
  if (ActiveSimdKernels() == SimdKernels::kAvx)
    return UpdateAvx(alpha, beta, d, w, x, r, z, p, s, begin, end);
#endif
  return UpdateGeneric(alpha, beta, d, w, x, r, z, p, s, begin, end);
}

double DotRows(const double* a, const double* b, int begin, int end) {
#if defined(__x86_64__)
  if (ActiveSimdKernels() == SimdKernels::kAvx) return DotAvx(a, b, begin, end);
#endif
  return DotGeneric(a, b, begin, end);
}

bool AllFiniteValues(const double* values, std::ptrdiff_t n) {
#if defined(__x86_64__)
  if (ActiveSimdKernels() == SimdKernels::kAvx) return AllFiniteAvx(values, n);
#endif
  return AllFiniteGeneric(values, n);
}

}  // namespace gipsi
