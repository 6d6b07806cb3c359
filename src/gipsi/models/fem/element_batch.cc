// ElementBatch, the element-wise default of SolidMaterial::ElementStressAndStiffnessBatch, and
// the vector-lane versions of CorotationalSolid's and NeoHookeanSolid's closed-form element
// stiffnesses (solid_laws.h).

#include <cmath>
#include <cstdint>

#include "gipsi/models/fem/solid_laws.h"
#include "gipsi/numerics/simd.h"
#include "gipsi/numerics/simd_v4.h"

namespace gipsi {

void ElementBatch::SetInput(int lane, const Mat3& f, const TetGradients& grad, double vol,
                            const MaterialPoint& point) {
  for (int k = 0; k < 9; ++k) F[k][lane] = f.data()[k];
  for (int k = 0; k < 12; ++k) g[k][lane] = grad.data()[k];
  volume[lane] = vol;
  mp[lane] = point;
}

Mat3 ElementBatch::InputF(int lane) const {
  Mat3 f;
  for (int k = 0; k < 9; ++k) f.data()[k] = F[k][lane];
  return f;
}

TetGradients ElementBatch::InputGradients(int lane) const {
  TetGradients grad;
  for (int k = 0; k < 12; ++k) grad.data()[k] = g[k][lane];
  return grad;
}

void ElementBatch::SetOutput(int lane, bool success, const Mat3& stress, const Mat12& stiffness) {
  ok[lane] = success;
  for (int k = 0; k < 9; ++k) P[k][lane] = stress.data()[k];
  for (int k = 0; k < 144; ++k) K[k][lane] = stiffness.data()[k];
}

Mat3 ElementBatch::OutputP(int lane) const {
  Mat3 stress;
  for (int k = 0; k < 9; ++k) stress.data()[k] = P[k][lane];
  return stress;
}

Mat12 ElementBatch::OutputK(int lane) const {
  Mat12 stiffness;
  for (int k = 0; k < 144; ++k) stiffness.data()[k] = K[k][lane];
  return stiffness;
}

namespace {

void ElementWise(const SolidMaterial& law, ElementBatch& batch, int lane) {
  Mat3 P;
  Mat12 K;
  const bool ok = law.ElementStressAndStiffness(
      batch.InputF(lane), batch.mp[lane], batch.InputGradients(lane), batch.volume[lane], P, K);
  batch.SetOutput(lane, ok, P, K);
}

}  // namespace

void SolidMaterial::ElementStressAndStiffnessBatch(ElementBatch& batch) const {
  for (int lane = 0; lane < batch.count; ++lane) ElementWise(*this, batch, lane);
}

namespace {

using simd::Load;
using simd::Store;
using simd::V4d;
using simd::V4i;

/// A 3×3 matrix of lanes, column-major: (i, j) at m[i + 3j].
struct M3 {
  V4d m[9];
};

GIPSI_SIMD_INLINE void Splat(V4d& v, double x) { v = V4d{x, x, x, x}; }

// det = det(a) and t = cof(a) = det(a) a⁻ᵀ (cofactors), lane by lane.
GIPSI_SIMD_INLINE void Cofactors(const M3& a, M3& t, V4d& det) {
  const V4d* m = a.m;
  t.m[0] = m[4] * m[8] - m[7] * m[5];
  t.m[1] = m[6] * m[5] - m[3] * m[8];
  t.m[2] = m[3] * m[7] - m[6] * m[4];
  t.m[3] = m[7] * m[2] - m[1] * m[8];
  t.m[4] = m[0] * m[8] - m[6] * m[2];
  t.m[5] = m[6] * m[1] - m[0] * m[7];
  t.m[6] = m[1] * m[5] - m[4] * m[2];
  t.m[7] = m[3] * m[2] - m[0] * m[5];
  t.m[8] = m[0] * m[4] - m[3] * m[1];
  det = m[0] * t.m[0] + m[1] * t.m[1] + m[2] * t.m[2];
}

GIPSI_SIMD_INLINE void SquaredNorm(const M3& a, V4d& sum) {
  sum = a.m[0] * a.m[0];
  for (int k = 1; k < 9; ++k) sum += a.m[k] * a.m[k];
}

GIPSI_SIMD_INLINE void Abs(const V4d& x, V4d& out) {
  const V4i sign = {INT64_MIN, INT64_MIN, INT64_MIN, INT64_MIN};
  out = (V4d)((V4i)x & ~sign);
}

// The element-wise path's scaled Newton polar iteration (solid_laws.cc, FastPolar) in the lanes:
// R ← ½(γR + γ⁻¹R⁻ᵀ), γ = (‖R⁻¹‖_F / ‖R‖_F)^½ for the first four steps, until a step changes R
// by ≤ 1e-8 (max norm). A lane that has converged keeps its iterate (bitwise select) while the
// others go on. Returns a mask of the converged lanes (all ones) after at most 30 steps.
GIPSI_SIMD_INLINE void PolarLanes(const M3& F, M3& R, V4i& converged) {
  R = F;
  converged = V4i{0, 0, 0, 0};
  V4d half, tolerance;
  Splat(half, 0.5);
  Splat(tolerance, 1e-8);
  for (int it = 0; it < 30; ++it) {
    M3 inverse_t;
    V4d det;
    Cofactors(R, inverse_t, det);
    const V4d inv_det = 1.0 / det;
    for (V4d& v : inverse_t.m) v *= inv_det;
    V4d gamma, inv_gamma;
    if (it < 4) {
      V4d num, den;
      SquaredNorm(inverse_t, num);
      SquaredNorm(R, den);
      double ratio[4];
      Store(ratio, num / den);
      for (double& r : ratio) r = std::sqrt(std::sqrt(r));
      Load(gamma, ratio);
      inv_gamma = 1.0 / gamma;
    } else {
      Splat(gamma, 1.0);
      Splat(inv_gamma, 1.0);
    }
    V4d change = V4d{0.0, 0.0, 0.0, 0.0};
    M3 next;
    for (int k = 0; k < 9; ++k) {
      next.m[k] = half * (gamma * R.m[k] + inverse_t.m[k] * inv_gamma);
      V4d delta;
      Abs(next.m[k] - R.m[k], delta);
      const V4i larger = (V4i)(delta > change);
      change = (V4d)(((V4i)delta & larger) | ((V4i)change & ~larger));
    }
    // Lanes still iterating take the new iterate.
    for (int k = 0; k < 9; ++k)
      R.m[k] = (V4d)(((V4i)next.m[k] & ~converged) | ((V4i)R.m[k] & converged));
    converged |= (V4i)(change <= tolerance);
    bool all = true;
    for (int l = 0; l < 4; ++l) all = all && converged[l] != 0;
    if (all) return;
  }
}

// Entry (i, k) of block (a, b) of K, a ≤ b, and its mirror in block (b, a); adds it to the lanes'
// finiteness sum (x · 0 is 0 for a finite x and NaN otherwise).
GIPSI_SIMD_INLINE void StoreStiffness(ElementBatch& batch, int a, int b, int i, int k, const V4d& v,
                                      V4d& finite_check) {
  finite_check += v * 0.0;
  Store(batch.K[(3 * a + i) + 12 * (3 * b + k)], v);
  if (a != b) Store(batch.K[(3 * b + k) + 12 * (3 * a + i)], v);
}

GIPSI_SIMD_INLINE void Select(const V4i& mask, const V4d& yes, const V4d& no, V4d& out) {
  out = (V4d)(((V4i)yes & mask) | ((V4i)no & ~mask));
}

// `fast` comes in as the lanes to try (all ones) and goes out as those the vector path
// evaluated in full: F finite and comfortably away from inversion (the element-wise FastPolar's
// test, det F > 1e-6 ‖F‖³), the polar iteration converged, P and K finite. The others are
// computed on F = I, to be replaced by the caller.
GIPSI_SIMD_INLINE void CorotationalLanes(const double* params, ElementBatch& batch, V4i& fast) {
  const double lambda_value = params[0], mu_value = params[1];
  M3 F, R;
  for (int k = 0; k < 9; ++k) Load(F.m[k], batch.F[k]);
  {
    M3 cofactors;
    V4d det, norm2;
    Cofactors(F, cofactors, det);
    SquaredNorm(F, norm2);
    double norm[4];
    Store(norm, norm2);
    for (double& n : norm) n = std::sqrt(n);
    V4d norm_v;
    Load(norm_v, norm);
    fast &= (V4i)(det > 1e-6 * norm2 * norm_v);  // false for a non-finite F
    V4d one, zero;
    Splat(one, 1.0);
    Splat(zero, 0.0);
    for (int k = 0; k < 9; ++k) Select(fast, F.m[k], k % 4 == 0 ? one : zero, F.m[k]);
  }
  V4i converged;
  PolarLanes(F, R, converged);
  fast &= converged;
  // x · 0 is 0 for a finite x and NaN otherwise: one sum tells whether a lane's P and K are.
  V4d finite_check;
  Splat(finite_check, 0.0);
  // S = sym(RᵀF), its trace, and M = (tr(S) I − S)⁻¹.
  M3 S;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      S.m[i + 3 * j] = R.m[3 * i] * F.m[3 * j] + R.m[3 * i + 1] * F.m[3 * j + 1] +
                       R.m[3 * i + 2] * F.m[3 * j + 2];
  V4d half;
  Splat(half, 0.5);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < j; ++i) {
      const V4d v = half * (S.m[i + 3 * j] + S.m[j + 3 * i]);
      S.m[i + 3 * j] = v;
      S.m[j + 3 * i] = v;
    }
  const V4d trace_s = S.m[0] + S.m[4] + S.m[8];
  M3 A, M;
  for (int k = 0; k < 9; ++k) A.m[k] = -S.m[k];
  for (int i = 0; i < 3; ++i) A.m[4 * i] += trace_s;
  V4d det;
  Cofactors(A, M, det);  // A is symmetric: cof(A) = det(A) A⁻¹
  const V4d inv_det = 1.0 / det;
  for (V4d& v : M.m) v *= inv_det;

  V4d lambda, two_mu, three;
  Splat(lambda, lambda_value);
  Splat(two_mu, 2 * mu_value);
  Splat(three, 3.0);
  const V4d tr = trace_s - three;
  // P = 2μ (F − R) + λ tr(S − I) R.
  const V4d lambda_tr = lambda * tr;
  for (int k = 0; k < 9; ++k) {
    const V4d p = two_mu * (F.m[k] - R.m[k]) + lambda_tr * R.m[k];
    finite_check += p * 0.0;
    Store(batch.P[k], p);
  }
  V4d volume;
  Load(volume, batch.volume);
  const V4d c = volume * (lambda_tr - two_mu);
  const V4d v_lambda = volume * lambda;
  const V4d v_two_mu = volume * two_mu;
  // q_a = R g_a, X_a = R [g_a]×, Y_a = c X_a M.
  V4d g[4][3], q[4][3];
  M3 X[4], Y[4];
  for (int a = 0; a < 4; ++a) {
    for (int j = 0; j < 3; ++j) Load(g[a][j], batch.g[j + 3 * a]);
    for (int i = 0; i < 3; ++i)
      q[a][i] = R.m[i] * g[a][0] + R.m[i + 3] * g[a][1] + R.m[i + 6] * g[a][2];
    for (int i = 0; i < 3; ++i) {
      X[a].m[i] = R.m[i + 6] * g[a][1] - R.m[i + 3] * g[a][2];
      X[a].m[i + 3] = R.m[i] * g[a][2] - R.m[i + 6] * g[a][0];
      X[a].m[i + 6] = R.m[i + 3] * g[a][0] - R.m[i] * g[a][1];
    }
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i)
        Y[a].m[i + 3 * j] = c * (X[a].m[i] * M.m[3 * j] + X[a].m[i + 3] * M.m[3 * j + 1] +
                                 X[a].m[i + 6] * M.m[3 * j + 2]);
  }
  // K_ab = Y_a X_bᵀ + Vλ q_a q_bᵀ + 2μV (g_a·g_b) I, a ≤ b, mirrored.
  for (int b = 0; b < 4; ++b)
    for (int a = 0; a <= b; ++a) {
      const V4d gg = v_two_mu * (g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2]);
      for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i) {
          V4d v = Y[a].m[i] * X[b].m[k] + Y[a].m[i + 3] * X[b].m[k + 3] +
                  Y[a].m[i + 6] * X[b].m[k + 6] + v_lambda * q[a][i] * q[b][k];
          if (i == k) v += gg;
          StoreStiffness(batch, a, b, i, k, v, finite_check);
        }
    }
  fast &= (V4i)(finite_check == finite_check);
}

// NeoHookeanSolid's closed form in the lanes. `fast` as for CorotationalLanes: J > kMinJacobian
// (false for a non-finite F) and P, K finite; the other lanes compute on F = I.
GIPSI_SIMD_INLINE void NeoHookeanLanes(const double* params, ElementBatch& batch, V4i& fast) {
  const double lambda_value = params[0], mu_value = params[1];
  M3 F, H;
  for (int k = 0; k < 9; ++k) Load(F.m[k], batch.F[k]);
  V4d J;
  Cofactors(F, H, J);
  V4d min_j;
  Splat(min_j, kMinJacobian);
  fast &= (V4i)(J > min_j);
  V4d one, zero;
  Splat(one, 1.0);
  Splat(zero, 0.0);
  for (int k = 0; k < 9; ++k) Select(fast, F.m[k], k % 4 == 0 ? one : zero, F.m[k]);
  Cofactors(F, H, J);  // again for the lanes just set to I: H = cof(F) / J = F⁻ᵀ
  const V4d inv_j = 1.0 / J;
  for (V4d& v : H.m) v *= inv_j;
  double logs[4];
  Store(logs, J);
  for (double& v : logs) v = std::log(v);
  V4d log_j;
  Load(log_j, logs);
  V4d lambda, mu;
  Splat(lambda, lambda_value);
  Splat(mu, mu_value);
  V4d finite_check = zero;
  // P = μ F + (λ ln J − μ) H.
  const V4d ph = lambda * log_j - mu;
  for (int k = 0; k < 9; ++k) {
    const V4d p = mu * F.m[k] + ph * H.m[k];
    finite_check += p * 0.0;
    Store(batch.P[k], p);
  }
  V4d volume;
  Load(volume, batch.volume);
  const V4d c = volume * (mu - lambda * log_j);
  const V4d v_lambda = volume * lambda;
  const V4d v_mu = volume * mu;
  V4d g[4][3], h[4][3];
  for (int a = 0; a < 4; ++a) {
    for (int j = 0; j < 3; ++j) Load(g[a][j], batch.g[j + 3 * a]);
    for (int i = 0; i < 3; ++i)
      h[a][i] = H.m[i] * g[a][0] + H.m[i + 3] * g[a][1] + H.m[i + 6] * g[a][2];
  }
  // K_ab = V [μ (g_a·g_b) I + c h_b h_aᵀ + λ h_a h_bᵀ], a ≤ b, mirrored.
  for (int b = 0; b < 4; ++b)
    for (int a = 0; a <= b; ++a) {
      const V4d gg = v_mu * (g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2]);
      for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i) {
          V4d v = c * (h[b][i] * h[a][k]) + v_lambda * (h[a][i] * h[b][k]);
          if (i == k) v += gg;
          StoreStiffness(batch, a, b, i, k, v, finite_check);
        }
    }
  fast &= (V4i)(finite_check == finite_check);
}

// GuccioneSolid's closed form (solid_laws.h) in the lanes, with the active tension: params C,
// b_f, b_t, b_fs, κ. `fast` as for the others: J > kMinJacobian and Q ≤ kMaxExponent (both false
// for a non-finite F) and P, K finite; the other lanes compute on F = I.
GIPSI_SIMD_INLINE void GuccioneLanes(const double* params, ElementBatch& batch, V4i& fast) {
  const double C = params[0], bf = params[1], bt = params[2], bfs = params[3];
  const double kappa_value = params[4];
  const double b[9] = {bf, bfs, bfs, bfs, bt, bt, bfs, bt, bt};  // B, symmetric
  M3 F, H, A;
  for (int k = 0; k < 9; ++k) Load(F.m[k], batch.F[k]);
  double axes[9][4], tension[4];
  for (int l = 0; l < 4; ++l) {
    for (int k = 0; k < 9; ++k) axes[k][l] = batch.mp[l].axes.data()[k];
    tension[l] = batch.mp[l].active_tension;
  }
  for (int k = 0; k < 9; ++k) Load(A.m[k], axes[k]);
  V4d J, zero, one;
  Splat(zero, 0.0);
  Splat(one, 1.0);
  Cofactors(F, H, J);
  V4d min_j;
  Splat(min_j, kMinJacobian);
  fast &= (V4i)(J > min_j);
  for (int k = 0; k < 9; ++k) Select(fast, F.m[k], k % 4 == 0 ? one : zero, F.m[k]);
  Cofactors(F, H, J);
  const V4d inv_j = 1.0 / J;
  for (V4d& v : H.m) v *= inv_j;
  // G = F A; E' = ½ (GᵀG − I); B ∘ E'; Q = Σ E' ∘ (B ∘ E').
  M3 G, be;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      G.m[i + 3 * j] =
          F.m[i] * A.m[3 * j] + F.m[i + 3] * A.m[3 * j + 1] + F.m[i + 6] * A.m[3 * j + 2];
  V4d half, q;
  Splat(half, 0.5);
  Splat(q, 0.0);
  for (int n = 0; n < 3; ++n)
    for (int m = 0; m < 3; ++m) {
      V4d e = half * (G.m[3 * m] * G.m[3 * n] + G.m[3 * m + 1] * G.m[3 * n + 1] +
                      G.m[3 * m + 2] * G.m[3 * n + 2]);
      if (m == n) e -= half;
      be.m[m + 3 * n] = b[m + 3 * n] * e;
      q += e * be.m[m + 3 * n];
    }
  V4d max_q;
  Splat(max_q, GuccioneSolid::kMaxExponent);
  fast &= (V4i)(q <= max_q);
  double lanes_q[4], lanes_j[4];
  Store(lanes_q, q);
  Store(lanes_j, J);
  for (int l = 0; l < 4; ++l) {
    lanes_q[l] = fast[l] != 0 ? C * std::exp(lanes_q[l]) : 0.0;
    lanes_j[l] = std::log(lanes_j[l]);
  }
  V4d c, log_j, kappa;
  Load(c, lanes_q);
  Load(log_j, lanes_j);
  Splat(kappa, kappa_value);
  // S = A (c B∘E') Aᵀ + Ta f fᵀ (f the first axis); P = F S + κ ln J H.
  M3 AS, S;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      AS.m[i + 3 * j] =
          c * (A.m[i] * be.m[3 * j] + A.m[i + 3] * be.m[3 * j + 1] + A.m[i + 6] * be.m[3 * j + 2]);
  V4d ta;
  Load(ta, tension);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      S.m[i + 3 * j] = AS.m[i] * A.m[j] + AS.m[i + 3] * A.m[j + 3] + AS.m[i + 6] * A.m[j + 6] +
                       ta * (A.m[i] * A.m[j]);
  V4d finite_check = zero;
  const V4d kappa_log_j = kappa * log_j;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const V4d p = F.m[i] * S.m[3 * j] + F.m[i + 3] * S.m[3 * j + 1] +
                    F.m[i + 6] * S.m[3 * j + 2] + kappa_log_j * H.m[i + 3 * j];
      finite_check += p * 0.0;
      Store(batch.P[i + 3 * j], p);
    }
  // Per node: r_a = Aᵀ g_a, B_a (6×3, Voigt rows), d ∘ B_a, τ_a = B_aᵀ s, h_a = H g_a, S g_a.
  constexpr int kPair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};
  V4d g[4][3], h[4][3], sg[4][3], tau[4][3], B[4][6][3], dB[4][6][3];
  for (int a = 0; a < 4; ++a) {
    for (int j = 0; j < 3; ++j) Load(g[a][j], batch.g[j + 3 * a]);
    V4d r[3];
    for (int n = 0; n < 3; ++n)
      r[n] = A.m[3 * n] * g[a][0] + A.m[3 * n + 1] * g[a][1] + A.m[3 * n + 2] * g[a][2];
    for (int i = 0; i < 3; ++i) {
      h[a][i] = H.m[i] * g[a][0] + H.m[i + 3] * g[a][1] + H.m[i + 6] * g[a][2];
      sg[a][i] = S.m[i] * g[a][0] + S.m[i + 3] * g[a][1] + S.m[i + 6] * g[a][2];
      tau[a][i] = zero;
    }
    for (int v = 0; v < 6; ++v) {
      const int m = kPair[v][0], n = kPair[v][1];
      const double w = m == n ? 0.5 : 1.0;
      const double d = (m == n ? 1.0 : 0.5) * b[m + 3 * n];
      for (int i = 0; i < 3; ++i) {
        B[a][v][i] = w * (G.m[i + 3 * m] * r[n] + G.m[i + 3 * n] * r[m]);
        dB[a][v][i] = d * B[a][v][i];
        tau[a][i] += B[a][v][i] * be.m[m + 3 * n];
      }
    }
  }
  V4d volume;
  Load(volume, batch.volume);
  const V4d two_c = 2.0 * c;
  for (int bn = 0; bn < 4; ++bn)
    for (int a = 0; a <= bn; ++a) {
      const V4d gsg = g[a][0] * sg[bn][0] + g[a][1] * sg[bn][1] + g[a][2] * sg[bn][2];
      for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i) {
          V4d material = B[a][0][i] * dB[bn][0][k];
          for (int v = 1; v < 6; ++v) material += B[a][v][i] * dB[bn][v][k];
          V4d value = c * material + two_c * (tau[a][i] * tau[bn][k]) +
                      kappa * (h[a][i] * h[bn][k]) - kappa_log_j * (h[bn][i] * h[a][k]);
          if (i == k) value += gsg;
          value *= volume;
          StoreStiffness(batch, a, bn, i, k, value, finite_check);
        }
    }
  fast &= (V4i)(finite_check == finite_check);
}

// One generic and one AVX copy of each lanes kernel.
#define GIPSI_LANES_COPIES(Name)                                             \
  void Name##Generic(const double* params, ElementBatch& batch, V4i& fast) { \
    Name##Lanes(params, batch, fast);                                        \
  }                                                                          \
  GIPSI_LANES_AVX(Name)
#if defined(__x86_64__)
#define GIPSI_LANES_AVX(Name)                                                              \
  __attribute__((target("avx"))) void Name##Avx(const double* params, ElementBatch& batch, \
                                                V4i& fast) {                               \
    Name##Lanes(params, batch, fast);                                                      \
  }
#else
#define GIPSI_LANES_AVX(Name)
#endif
GIPSI_LANES_COPIES(Corotational)
GIPSI_LANES_COPIES(NeoHookean)
GIPSI_LANES_COPIES(Guccione)
#undef GIPSI_LANES_COPIES
#undef GIPSI_LANES_AVX

}  // namespace

namespace {

using LanesKernel = void (*)(const double* params, ElementBatch& batch, V4i& fast);

// Runs a law's lanes kernel (AVX or generic) on a batch: every used lane is tried (those with an
// active tension only if the kernel takes it), unused lanes compute on lane 0's inputs; the
// lanes the kernel leaves out are evaluated element-wise, from their inputs as given.
void RunLanes(const SolidMaterial& law, const double* params, LanesKernel avx, LanesKernel generic,
              bool takes_active, ElementBatch& batch) {
  constexpr int kLanes = ElementBatch::kLanes;
  V4i fast = {0, 0, 0, 0};
  for (int l = 0; l < kLanes; ++l) {
    if (l < batch.count) {
      if (takes_active || batch.mp[l].active_tension == 0) fast[l] = -1;
    } else {
      for (int k = 0; k < 12; ++k) batch.g[k][l] = batch.g[k][0];
      batch.volume[l] = batch.volume[0];
      for (int k = 0; k < 9; ++k) batch.F[k][l] = batch.F[k][0];
      batch.mp[l] = batch.mp[0];
    }
  }
  (ActiveSimdKernels() == SimdKernels::kAvx && avx ? avx : generic)(params, batch, fast);
  for (int l = 0; l < batch.count; ++l) {
    if (fast[l] != 0)
      batch.ok[l] = true;
    else
      ElementWise(law, batch, l);  // its F is unchanged in the batch
  }
}

#if defined(__x86_64__)
constexpr LanesKernel kCorotationalAvx = CorotationalAvx;
constexpr LanesKernel kNeoHookeanAvx = NeoHookeanAvx;
constexpr LanesKernel kGuccioneAvx = GuccioneAvx;
#else
constexpr LanesKernel kCorotationalAvx = nullptr;
constexpr LanesKernel kNeoHookeanAvx = nullptr;
constexpr LanesKernel kGuccioneAvx = nullptr;
#endif

}  // namespace

void CorotationalSolid::ElementStressAndStiffnessBatch(ElementBatch& batch) const {
  const double params[] = {lame_.lambda, lame_.mu};
  RunLanes(*this, params, kCorotationalAvx, CorotationalGeneric, false, batch);
}

void NeoHookeanSolid::ElementStressAndStiffnessBatch(ElementBatch& batch) const {
  const double params[] = {lame_.lambda, lame_.mu};
  RunLanes(*this, params, kNeoHookeanAvx, NeoHookeanGeneric, false, batch);
}

void GuccioneSolid::ElementStressAndStiffnessBatch(ElementBatch& batch) const {
  const double params[] = {params_.C, params_.bf, params_.bt, params_.bfs, params_.bulk_modulus};
  RunLanes(*this, params, kGuccioneAvx, GuccioneGeneric, true, batch);
}

}  // namespace gipsi
