#include "gipsi/models/fem/solid_laws.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>

#include <fmt/format.h>
#include <Eigen/LU>
#include <Eigen/SVD>

#include "gipsi/base/error.h"

namespace gipsi {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Vec9 = Eigen::Matrix<double, 9, 1>;
using Mat69 = Eigen::Matrix<double, 6, 9>;

/// Voigt order of the symmetric index pairs: normal (0,0), (1,1), (2,2), then shears (1,2),
/// (0,2), (0,1).
constexpr int kVoigt[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};

/// The active PK2 stress S_a = Ta f ⊗ f [Pa].
Mat3 ActivePk2(const MaterialPoint& mp) {
  const Vec3 f = mp.axes.col(0);
  return mp.active_tension * (f * f.transpose());
}

/// The active energy Ta E_ff = Ta/2 (|F f|² − 1) [Pa].
double ActiveEnergy(const Mat3& F, const MaterialPoint& mp) {
  if (mp.active_tension == 0) return 0;
  return 0.5 * mp.active_tension * ((F * mp.axes.col(0)).squaredNorm() - 1.0);
}

/// Adds the geometric term δP = δF S of a PK2 stress S (symmetric):
/// dPdF(i + 3j, k + 3l) += δ_ik S(l, j).
void AddGeometricTangent(const Mat3& S, Mat9& dPdF) {
  for (int l = 0; l < 3; ++l) {
    for (int j = 0; j < 3; ++j) {
      const double s = S(l, j);
      for (int i = 0; i < 3; ++i) dPdF(i + 3 * j, i + 3 * l) += s;
    }
  }
}

/// Adds the tangent of the volumetric energy κ/2 (ln J)², whose stress is κ ln J H (H = F⁻ᵀ):
/// dPdF(i + 3j, k + 3l) += κ (H_ij H_kl − ln J H_il H_kj).
void AddLogVolumetricTangent(const Mat3& H, double kappa, double log_j, Mat9& dPdF) {
  const double c = -kappa * log_j;
  for (int l = 0; l < 3; ++l) {
    for (int k = 0; k < 3; ++k) {
      const double h_kl = kappa * H(k, l);
      for (int j = 0; j < 3; ++j) {
        const double h_kj = c * H(k, j);
        for (int i = 0; i < 3; ++i) dPdF(i + 3 * j, k + 3 * l) += H(i, j) * h_kl + H(i, l) * h_kj;
      }
    }
  }
}

/// An energy that is NaN (a non-finite F) is reported as +infinity, outside the domain.
double InfIfNan(double w) { return std::isnan(w) ? kInf : w; }

}  // namespace

LameParameters LameFromYoungPoisson(double youngs_modulus, double poisson_ratio) {
  GIPSI_CHECK(std::isfinite(youngs_modulus) && youngs_modulus > 0,
              "Young's modulus must be positive, got {}", youngs_modulus);
  GIPSI_CHECK(poisson_ratio > -1 && poisson_ratio < 0.5,
              "Poisson ratio must lie in (-1, 0.5), got {}", poisson_ratio);
  LameParameters lame;
  lame.lambda = youngs_modulus * poisson_ratio / ((1 + poisson_ratio) * (1 - 2 * poisson_ratio));
  lame.mu = youngs_modulus / (2 * (1 + poisson_ratio));
  return lame;
}

void SignedSvd(const Mat3& F, Mat3& U, Vec3& sigma, Mat3& V) {
  const Eigen::JacobiSVD<Mat3, Eigen::NoQRPreconditioner> svd(
      F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (svd.info() != Eigen::Success) {  // a non-finite F: Eigen leaves the factors unset
    U.setIdentity();
    V.setIdentity();
    sigma.setConstant(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  U = svd.matrixU();
  V = svd.matrixV();
  sigma = svd.singularValues();  // non-negative, decreasing
  // A reflection in U or V moves to the smallest singular value, keeping F = U Σ Vᵀ.
  if (U.determinant() < 0) {
    U.col(2) = -U.col(2);
    sigma(2) = -sigma(2);
  }
  if (V.determinant() < 0) {
    V.col(2) = -V.col(2);
    sigma(2) = -sigma(2);
  }
}

namespace {

bool FastPolar(const Mat3& F, Mat3& R) {
  // Scaled Newton iteration X ← ½(γX + γ⁻¹X⁻ᵀ) with the Frobenius-norm scaling
  // γ = (‖X⁻¹‖_F / ‖X‖_F)^½ (Higham, "Computing the polar decomposition — with applications",
  // SIAM J. Sci. Stat. Comput. 7, 1986; it needs only the inverse the step computes anyway, where
  // the determinant scaling |det X|^(−1/3) cost a cube root): quadratic convergence to the
  // rotation of F = R S for det F > 0, in 3–5 iterations of a 3×3 inverse (much cheaper than a
  // Jacobi SVD) and to full precision near F = I.
  const double det = F.determinant();
  if (!(det > 1e-6 * F.squaredNorm() * F.norm())) return false;  // near or past inversion
  R = F;
  for (int it = 0; it < 30; ++it) {
    const Mat3 inverse_t = R.inverse().transpose();
    const double gamma =
        it < 4 ? std::sqrt(std::sqrt(inverse_t.squaredNorm() / R.squaredNorm())) : 1.0;
    const Mat3 next = 0.5 * (gamma * R + inverse_t / gamma);
    const double change = (next - R).lpNorm<Eigen::Infinity>();
    R = next;
    // Newton's iteration for the polar factor converges quadratically: a step that changed X
    // by δ leaves an error of about δ²/2 (in the singular values, σ ← (σ + 1/σ)/2), so after a
    // change of 1e-8 the new iterate is within ~5e-17 of R, round-off. Waiting for a change
    // below 1e-15 cost one more iteration in most elements (4.6 on average in the FEM
    // benchmark).
    if (change <= 1e-8) return true;
  }
  return (R.transpose() * R - Mat3::Identity()).lpNorm<Eigen::Infinity>() < 1e-12;
}

}  // namespace

bool SolidMaterial::ElementStressAndStiffness(const Mat3& F, const MaterialPoint& mp,
                                              const TetGradients& g, double volume, Mat3& P,
                                              Mat12& K) const {
  Mat9 C;
  if (!StressAndTangent(F, mp, P, C)) return false;
  // T_b(:, k) = Σ_l C(:, k + 3l) g_b[l]  (9 by 3 per node b), then
  // K_ab(i, k) = V Σ_j g_a[j] T_b(i + 3j, k).
  for (int b = 0; b < 4; ++b) {
    Eigen::Matrix<double, 9, 3> t;
    for (int k = 0; k < 3; ++k)
      t.col(k) = C.col(k) * g(0, b) + C.col(k + 3) * g(1, b) + C.col(k + 6) * g(2, b);
    for (int a = 0; a < 4; ++a)
      K.block<3, 3>(3 * a, 3 * b) =
          volume * (g(0, a) * t.block<3, 3>(0, 0) + g(1, a) * t.block<3, 3>(3, 0) +
                    g(2, a) * t.block<3, 3>(6, 0));
  }
  return true;
}

IsotropicSolid::IsotropicSolid(double youngs_modulus, double poisson_ratio)
    : youngs_modulus_(youngs_modulus),
      poisson_ratio_(poisson_ratio),
      lame_(LameFromYoungPoisson(youngs_modulus, poisson_ratio)) {}

// ---------------------------------------------------------------------------------------------
// Linear

LinearSolid::LinearSolid(double youngs_modulus, double poisson_ratio)
    : IsotropicSolid(youngs_modulus, poisson_ratio) {
  tangent_.setZero();
  for (int l = 0; l < 3; ++l) {
    for (int k = 0; k < 3; ++k) {
      tangent_(k + 3 * l, k + 3 * l) += lame_.mu;  // μ δ_ik δ_jl
      tangent_(l + 3 * k, k + 3 * l) += lame_.mu;  // μ δ_il δ_jk
      if (k == l) {
        for (int i = 0; i < 3; ++i) tangent_(i + 3 * i, k + 3 * l) += lame_.lambda;
      }
    }
  }
}

double LinearSolid::Energy(const Mat3& F, const MaterialPoint& mp) const {
  const Mat3 eps = 0.5 * (F + F.transpose()) - Mat3::Identity();
  const double tr = eps.trace();
  return InfIfNan(lame_.mu * eps.squaredNorm() + 0.5 * lame_.lambda * tr * tr +
                  ActiveEnergy(F, mp));
}

bool LinearSolid::Stress(const Mat3& F, const MaterialPoint& mp, Mat3& P) const {
  const Mat3 eps = 0.5 * (F + F.transpose()) - Mat3::Identity();
  P = (2 * lame_.mu) * eps;
  P.diagonal().array() += lame_.lambda * eps.trace();
  if (mp.active_tension != 0) P.noalias() += F * ActivePk2(mp);
  return P.allFinite();
}

bool LinearSolid::StressAndTangent(const Mat3& F, const MaterialPoint& mp, Mat3& P,
                                   Mat9& dPdF) const {
  dPdF = tangent_;
  if (mp.active_tension != 0) AddGeometricTangent(ActivePk2(mp), dPdF);
  return Stress(F, mp, P);
}

// ---------------------------------------------------------------------------------------------
// Corotational

CorotationalSolid::CorotationalSolid(double youngs_modulus, double poisson_ratio)
    : IsotropicSolid(youngs_modulus, poisson_ratio) {}

double CorotationalSolid::Energy(const Mat3& F, const MaterialPoint& mp) const {
  if (!F.allFinite()) return kInf;
  Mat3 U, V;
  Vec3 sigma;
  SignedSvd(F, U, sigma, V);
  const double tr = sigma.sum() - 3;
  return InfIfNan(lame_.mu * (sigma.array() - 1).matrix().squaredNorm() +
                  0.5 * lame_.lambda * tr * tr + ActiveEnergy(F, mp));
}

bool CorotationalSolid::Stress(const Mat3& F, const MaterialPoint& mp, Mat3& P) const {
  if (!F.allFinite()) return false;
  Mat3 R;
  double trace_s = 0;
  if (FastPolar(F, R)) {
    trace_s = (R.transpose() * F).trace();
  } else {
    Mat3 U, V;
    Vec3 sigma;
    SignedSvd(F, U, sigma, V);
    R = U * V.transpose();
    trace_s = sigma.sum();
  }
  P = (2 * lame_.mu) * (F - R) + (lame_.lambda * (trace_s - 3)) * R;
  if (mp.active_tension != 0) P.noalias() += F * ActivePk2(mp);
  return P.allFinite();
}

bool CorotationalSolid::RotationAndInverse(const Mat3& F, Mat3& R, double& tr, Mat3& inv) const {
  if (!F.allFinite()) return false;
  if (FastPolar(F, R)) {
    // S = RᵀF is symmetric positive definite here, so tr(S) I − S is too (its eigenvalues are
    // sums of two singular values): invert it directly.
    Mat3 S = R.transpose() * F;
    S = 0.5 * (S + S.transpose());
    tr = S.trace() - 3;
    inv = (Mat3::Identity() * S.trace() - S).inverse();
  } else {
    Mat3 U, V;
    Vec3 sigma;
    SignedSvd(F, U, sigma, V);
    R = U * V.transpose();
    tr = sigma.sum() - 3;
    // (tr(S) I − S)⁻¹ = V diag(1 / (σ_j + σ_k)) Vᵀ, the sums clamped (see the header).
    const Vec3 sums(std::max(sigma(1) + sigma(2), kMinSingularSum),
                    std::max(sigma(0) + sigma(2), kMinSingularSum),
                    std::max(sigma(0) + sigma(1), kMinSingularSum));
    inv = V * sums.cwiseInverse().asDiagonal() * V.transpose();
  }
  return true;
}

bool CorotationalSolid::StressAndTangent(const Mat3& F, const MaterialPoint& mp, Mat3& P,
                                         Mat9& dPdF) const {
  Mat3 R, inv;
  double tr = 0;
  if (!RotationAndInverse(F, R, tr, inv)) return false;
  P = (2 * lame_.mu) * (F - R) + (lame_.lambda * tr) * R;

  // δP = 2μ δF + λ (R:δF) R + (λ tr(S − I) − 2μ) δR.
  const Eigen::Map<const Vec9> vec_r(R.data());
  dPdF.noalias() = lame_.lambda * (vec_r * vec_r.transpose());
  dPdF.diagonal().array() += 2 * lame_.mu;
  const double c_rot = lame_.lambda * tr - 2 * lame_.mu;
  for (int l = 0; l < 3; ++l) {
    for (int k = 0; k < 3; ++k) {
      // δF = e_k e_lᵀ: RᵀδF − δFᵀR = r e_lᵀ − e_l rᵀ with r = Rᵀ e_k, whose axial vector is
      // e_l × r.
      const Vec3 r = R.row(k).transpose();
      const Vec3 w = inv * Vec3::Unit(l).cross(r);
      // δR = R [w]×, column q = R (w × e_q).
      Mat3 skew;
      skew << 0, -w(2), w(1), w(2), 0, -w(0), -w(1), w(0), 0;
      const Mat3 dr = R * skew;
      dPdF.col(k + 3 * l) += c_rot * Eigen::Map<const Vec9>(dr.data());
    }
  }
  if (mp.active_tension != 0) {
    const Mat3 sa = ActivePk2(mp);
    P.noalias() += F * sa;
    AddGeometricTangent(sa, dPdF);
  }
  return P.allFinite() && dPdF.allFinite();
}

bool CorotationalSolid::ElementStressAndStiffness(const Mat3& F, const MaterialPoint& mp,
                                                  const TetGradients& g, double volume, Mat3& P,
                                                  Mat12& K) const {
  Mat3 R, inv;
  double tr = 0;
  if (!RotationAndInverse(F, R, tr, inv)) return false;
  P = (2 * lame_.mu) * (F - R) + (lame_.lambda * tr) * R;
  const double c = volume * (lame_.lambda * tr - 2 * lame_.mu);
  const double lambda = volume * lame_.lambda;
  const double two_mu = volume * 2 * lame_.mu;
  Mat3 sa = Mat3::Zero();
  if (mp.active_tension != 0) {
    sa = volume * ActivePk2(mp);
    P.noalias() += F * ActivePk2(mp);
  }
  Eigen::Matrix<double, 3, 4> q;
  std::array<Mat3, 4> x, y;  // X_a = R [g_a]×, Y_a = c X_a M
  for (int a = 0; a < 4; ++a) {
    const Vec3 ga = g.col(a);
    q.col(a) = R * ga;
    // Column j of R [g]× is R (g × e_j).
    x[a].col(0) = R.col(2) * ga(1) - R.col(1) * ga(2);
    x[a].col(1) = R.col(0) * ga(2) - R.col(2) * ga(0);
    x[a].col(2) = R.col(1) * ga(0) - R.col(0) * ga(1);
    y[a].noalias() = c * (x[a] * inv);
  }
  for (int b = 0; b < 4; ++b) {
    for (int a = 0; a <= b; ++a) {
      Mat3 block;
      block.noalias() = y[a] * x[b].transpose();
      block.noalias() += lambda * (q.col(a) * q.col(b).transpose());
      block.diagonal().array() += two_mu * g.col(a).dot(g.col(b)) + g.col(a).dot(sa * g.col(b));
      K.block<3, 3>(3 * a, 3 * b) = block;
      if (a != b) K.block<3, 3>(3 * b, 3 * a) = block.transpose();
    }
  }
  return P.allFinite() && K.allFinite();
}

// ---------------------------------------------------------------------------------------------
// St Venant–Kirchhoff

StVenantKirchhoffSolid::StVenantKirchhoffSolid(double youngs_modulus, double poisson_ratio)
    : IsotropicSolid(youngs_modulus, poisson_ratio) {}

double StVenantKirchhoffSolid::Energy(const Mat3& F, const MaterialPoint& mp) const {
  const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
  const double tr = E.trace();
  return InfIfNan(lame_.mu * E.squaredNorm() + 0.5 * lame_.lambda * tr * tr + ActiveEnergy(F, mp));
}

bool StVenantKirchhoffSolid::Stress(const Mat3& F, const MaterialPoint& mp, Mat3& P) const {
  const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
  Mat3 S = (2 * lame_.mu) * E;
  S.diagonal().array() += lame_.lambda * E.trace();
  if (mp.active_tension != 0) S += ActivePk2(mp);
  P.noalias() = F * S;
  return P.allFinite();
}

bool StVenantKirchhoffSolid::StressAndTangent(const Mat3& F, const MaterialPoint& mp, Mat3& P,
                                              Mat9& dPdF) const {
  const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
  Mat3 S = (2 * lame_.mu) * E;
  S.diagonal().array() += lame_.lambda * E.trace();
  if (mp.active_tension != 0) S += ActivePk2(mp);
  P.noalias() = F * S;
  const Mat3 b = F * F.transpose();
  const double lambda = lame_.lambda;
  const double mu = lame_.mu;
  // dP_ij/dF_kl = δ_ik S_lj + λ F_ij F_kl + μ (b_ik δ_jl + F_il F_kj).
  for (int l = 0; l < 3; ++l) {
    for (int k = 0; k < 3; ++k) {
      const double lf_kl = lambda * F(k, l);
      for (int j = 0; j < 3; ++j) {
        const double mf_kj = mu * F(k, j);
        for (int i = 0; i < 3; ++i) {
          double v = F(i, j) * lf_kl + F(i, l) * mf_kj;
          if (j == l) v += mu * b(i, k);
          if (i == k) v += S(l, j);
          dPdF(i + 3 * j, k + 3 * l) = v;
        }
      }
    }
  }
  return P.allFinite() && dPdF.allFinite();
}

// ---------------------------------------------------------------------------------------------
// Neo-Hookean

NeoHookeanSolid::NeoHookeanSolid(double youngs_modulus, double poisson_ratio)
    : IsotropicSolid(youngs_modulus, poisson_ratio) {}

double NeoHookeanSolid::Energy(const Mat3& F, const MaterialPoint& mp) const {
  const double J = F.determinant();
  if (!(J > kMinJacobian)) return kInf;
  const double log_j = std::log(J);
  return InfIfNan(0.5 * lame_.mu * (F.squaredNorm() - 3) - lame_.mu * log_j +
                  0.5 * lame_.lambda * log_j * log_j + ActiveEnergy(F, mp));
}

bool NeoHookeanSolid::Stress(const Mat3& F, const MaterialPoint& mp, Mat3& P) const {
  const double J = F.determinant();
  if (!(J > kMinJacobian)) return false;
  const double log_j = std::log(J);
  const Mat3 H = F.inverse().transpose();
  P = lame_.mu * F + (lame_.lambda * log_j - lame_.mu) * H;
  if (mp.active_tension != 0) P.noalias() += F * ActivePk2(mp);
  return P.allFinite();
}

bool NeoHookeanSolid::StressAndTangent(const Mat3& F, const MaterialPoint& mp, Mat3& P,
                                       Mat9& dPdF) const {
  const double J = F.determinant();
  if (!(J > kMinJacobian)) return false;
  const double log_j = std::log(J);
  const Mat3 H = F.inverse().transpose();
  P = lame_.mu * F + (lame_.lambda * log_j - lame_.mu) * H;
  // dP_ij/dF_kl = μ δ_ik δ_jl + (μ − λ ln J) H_il H_kj + λ H_ij H_kl.
  const double c = lame_.mu - lame_.lambda * log_j;
  for (int l = 0; l < 3; ++l) {
    for (int k = 0; k < 3; ++k) {
      const double lh_kl = lame_.lambda * H(k, l);
      for (int j = 0; j < 3; ++j) {
        const double ch_kj = c * H(k, j);
        for (int i = 0; i < 3; ++i) dPdF(i + 3 * j, k + 3 * l) = H(i, l) * ch_kj + H(i, j) * lh_kl;
      }
    }
  }
  dPdF.diagonal().array() += lame_.mu;
  if (mp.active_tension != 0) {
    const Mat3 sa = ActivePk2(mp);
    P.noalias() += F * sa;
    AddGeometricTangent(sa, dPdF);
  }
  return P.allFinite() && dPdF.allFinite();
}

bool NeoHookeanSolid::ElementStressAndStiffness(const Mat3& F, const MaterialPoint& mp,
                                                const TetGradients& g, double volume, Mat3& P,
                                                Mat12& K) const {
  if (mp.active_tension != 0)
    return SolidMaterial::ElementStressAndStiffness(F, mp, g, volume, P, K);
  const double J = F.determinant();
  if (!(J > kMinJacobian)) return false;
  const double log_j = std::log(J);
  const Mat3 H = F.inverse().transpose();
  P = lame_.mu * F + (lame_.lambda * log_j - lame_.mu) * H;
  const Eigen::Matrix<double, 3, 4> h = H * g;
  const double c = volume * (lame_.mu - lame_.lambda * log_j);
  const double lambda = volume * lame_.lambda;
  const double mu = volume * lame_.mu;
  for (int b = 0; b < 4; ++b)
    for (int a = 0; a <= b; ++a) {
      Mat3 block =
          c * (h.col(b) * h.col(a).transpose()) + lambda * (h.col(a) * h.col(b).transpose());
      block.diagonal().array() += mu * g.col(a).dot(g.col(b));
      K.block<3, 3>(3 * a, 3 * b) = block;
      if (a != b) K.block<3, 3>(3 * b, 3 * a) = block.transpose();
    }
  return P.allFinite() && K.allFinite();
}

// ---------------------------------------------------------------------------------------------
// Guccione

namespace {

/// The Guccione kinematics at one F: J, ln J, E' = Aᵀ E A, B ∘ E' and Q.
struct GuccionePoint {
  double log_j = 0;
  double q = 0;
  Mat3 g;   // F A (3×3): its columns are the deformed fibre, sheet and normal directions
  Mat3 be;  // B ∘ E'
};

/// Fills `pt`; false outside the domain (J ≤ kMinJacobian, Q > kMaxExponent or not finite).
bool EvaluateGuccione(const Mat3& b, const Mat3& F, const Mat3& axes, GuccionePoint& pt) {
  const double J = F.determinant();
  if (!(J > kMinJacobian)) return false;
  pt.g.noalias() = F * axes;
  // E' = Aᵀ ½(FᵀF − I) A = ½((FA)ᵀ(FA) − I) since AᵀA = I.
  Mat3 e_fibre = 0.5 * (pt.g.transpose() * pt.g);
  e_fibre.diagonal().array() -= 0.5;
  pt.be = b.cwiseProduct(e_fibre);
  pt.q = e_fibre.cwiseProduct(pt.be).sum();
  if (!(pt.q <= GuccioneSolid::kMaxExponent)) return false;  // also rejects NaN
  pt.log_j = std::log(J);
  return true;
}

}  // namespace

GuccioneSolid::GuccioneSolid(const GuccioneParams& params) : params_(params) {
  GIPSI_CHECK(
      params.C > 0 && params.bf > 0 && params.bt > 0 && params.bfs > 0 && params.bulk_modulus > 0,
      "Guccione parameters must be positive (C {}, bf {}, bt {}, bfs {}, kappa {})", params.C,
      params.bf, params.bt, params.bfs, params.bulk_modulus);
  b_ << params.bf, params.bfs, params.bfs,  //
      params.bfs, params.bt, params.bt,     //
      params.bfs, params.bt, params.bt;
  // Small-strain moduli (formulas in the header).
  const double df = params.C * params.bf;
  const double dt = params.C * params.bt;
  const double kappa = params.bulk_modulus;
  const double num = df * dt + kappa * dt + 2 * kappa * df;
  const double e_fibre = num / (dt + 2 * kappa);
  const double e_cross = dt * num / (df * dt + kappa * dt + kappa * df);
  small_e_ = std::max(e_fibre, e_cross);
  const double bulk = kappa + params.C * (params.bf + 2 * params.bt) / 9;
  small_nu_ = (3 * bulk - small_e_) / (6 * bulk);
}

double GuccioneSolid::Energy(const Mat3& F, const MaterialPoint& mp) const {
  GuccionePoint pt;
  if (!EvaluateGuccione(b_, F, mp.axes, pt)) return kInf;
  return InfIfNan(0.5 * params_.C * std::expm1(pt.q) +
                  0.5 * params_.bulk_modulus * pt.log_j * pt.log_j + ActiveEnergy(F, mp));
}

bool GuccioneSolid::Stress(const Mat3& F, const MaterialPoint& mp, Mat3& P) const {
  GuccionePoint pt;
  if (!EvaluateGuccione(b_, F, mp.axes, pt)) return false;
  // F S = F A S' Aᵀ = (FA) S' Aᵀ.
  P.noalias() = (params_.C * std::exp(pt.q)) * (pt.g * pt.be * mp.axes.transpose());
  P.noalias() += (params_.bulk_modulus * pt.log_j) * F.inverse().transpose();
  if (mp.active_tension != 0) P.noalias() += F * ActivePk2(mp);
  return P.allFinite();
}

bool GuccioneSolid::StressAndTangent(const Mat3& F, const MaterialPoint& mp, Mat3& P,
                                     Mat9& dPdF) const {
  GuccionePoint pt;
  if (!EvaluateGuccione(b_, F, mp.axes, pt)) return false;
  const Mat3& A = mp.axes;
  const double c = params_.C * std::exp(pt.q);
  const Mat3 H = F.inverse().transpose();
  Mat3 S = A * (c * pt.be) * A.transpose();
  if (mp.active_tension != 0) S += ActivePk2(mp);
  P.noalias() = F * S;
  P.noalias() += (params_.bulk_modulus * pt.log_j) * H;

  // dε'/dvec(F) with engineering shears: for the pair (m, n), E'_mn = ½ (g_m·g_n − δ_mn), g = FA,
  // so ∂E'_mn/∂F_pq = ½ (g_pm A_qn + g_pn A_qm); shear rows are doubled.
  Mat69 jac;
  Vec6 s;
  Vec6 d;
  for (int a = 0; a < 6; ++a) {
    const int m = kVoigt[a][0];
    const int n = kVoigt[a][1];
    const double w = m == n ? 0.5 : 1.0;
    for (int q = 0; q < 3; ++q) {
      for (int p = 0; p < 3; ++p)
        jac(a, p + 3 * q) = w * (pt.g(p, m) * A(q, n) + pt.g(p, n) * A(q, m));
    }
    s(a) = pt.be(m, n);
    d(a) = (m == n ? 1.0 : 0.5) * b_(m, n);
  }
  // Material part: jacᵀ (dS'/dε') jac = c (jacᵀ diag(d) jac + 2 t tᵀ), t = jacᵀ s.
  const Mat69 djac = d.asDiagonal() * jac;
  dPdF.noalias() = jac.transpose().lazyProduct(djac);  // coefficient-wise: no GEMM blocking
  const Vec9 t = jac.transpose() * s;
  dPdF.noalias() += 2 * t * t.transpose();
  dPdF *= c;
  AddGeometricTangent(S, dPdF);
  AddLogVolumetricTangent(H, params_.bulk_modulus, pt.log_j, dPdF);
  return P.allFinite() && dPdF.allFinite();
}

bool GuccioneSolid::ElementStressAndStiffness(const Mat3& F, const MaterialPoint& mp,
                                              const TetGradients& g, double volume, Mat3& P,
                                              Mat12& K) const {
  GuccionePoint pt;
  if (!EvaluateGuccione(b_, F, mp.axes, pt)) return false;
  const Mat3& A = mp.axes;
  const double c = params_.C * std::exp(pt.q);
  const double kappa = params_.bulk_modulus;
  const Mat3 H = F.inverse().transpose();
  Mat3 S = A * (c * pt.be) * A.transpose();
  if (mp.active_tension != 0) S += ActivePk2(mp);
  P.noalias() = F * S;
  P.noalias() += (kappa * pt.log_j) * H;

  Vec6 s, d;
  for (int v = 0; v < 6; ++v) {
    const int m = kVoigt[v][0], n = kVoigt[v][1];
    s(v) = pt.be(m, n);
    d(v) = (m == n ? 1.0 : 0.5) * b_(m, n);
  }
  const Eigen::Matrix<double, 3, 4> r = A.transpose() * g;  // gradients in the fibre frame
  const Eigen::Matrix<double, 3, 4> h = H * g;
  const Eigen::Matrix<double, 3, 4> sg = S * g;
  std::array<Eigen::Matrix<double, 6, 3>, 4> B, dB;
  std::array<Vec3, 4> tau;
  for (int a = 0; a < 4; ++a) {
    for (int v = 0; v < 6; ++v) {
      const int m = kVoigt[v][0], n = kVoigt[v][1];
      const double w = m == n ? 0.5 : 1.0;
      B[a].row(v) = w * (pt.g.col(m) * r(n, a) + pt.g.col(n) * r(m, a)).transpose();
    }
    dB[a] = d.asDiagonal() * B[a];
    tau[a] = B[a].transpose() * s;
  }
  for (int b = 0; b < 4; ++b) {
    for (int a = 0; a <= b; ++a) {
      Mat3 block = c * (B[a].transpose() * dB[b] + 2 * tau[a] * tau[b].transpose());
      block.noalias() += kappa * (h.col(a) * h.col(b).transpose());
      block.noalias() -= (kappa * pt.log_j) * (h.col(b) * h.col(a).transpose());
      block.diagonal().array() += g.col(a).dot(sg.col(b));
      block *= volume;
      K.block<3, 3>(3 * a, 3 * b) = block;
      if (a != b) K.block<3, 3>(3 * b, 3 * a) = block.transpose();
    }
  }
  return P.allFinite() && K.allFinite();
}

// ---------------------------------------------------------------------------------------------
// Registration

namespace {

/// Reads and validates `youngs_modulus` and `poisson_ratio` (the only keys besides "law").
std::pair<double, double> ReadYoungPoisson(const JsonNode& node) {
  node.CheckKeys({"law", "youngs_modulus", "poisson_ratio"});
  const double youngs_modulus = node.Positive("youngs_modulus");
  const JsonNode nu_node = node.At("poisson_ratio");
  const double nu = nu_node.AsNumber();
  if (nu >= 0.5) {
    nu_node.Fail(fmt::format(
        "Poisson ratio {} must be below 0.5: 0.5 is an incompressible material, which these "
        "displacement-based laws cannot represent (the Lame parameter lambda is infinite); use "
        "a value such as 0.49 or 0.499 for a nearly incompressible one",
        nu));
  }
  if (nu <= -1) {
    nu_node.Fail(fmt::format(
        "Poisson ratio {} must be greater than -1 (the shear modulus would not be positive)", nu));
  }
  return {youngs_modulus, nu};
}

template <class Law>
void RegisterIsotropic(TypeRegistry& registry, const std::string& name, std::string description) {
  registry.materials.Register(
      name,
      [](const JsonNode& node) -> std::shared_ptr<const Material> {
        const auto [youngs_modulus, poisson_ratio] = ReadYoungPoisson(node);
        return std::make_shared<Law>(youngs_modulus, poisson_ratio);
      },
      std::move(description));
}

}  // namespace

void RegisterSolidLaws(TypeRegistry& registry) {
  RegisterIsotropic<LinearSolid>(
      registry, "Linear",
      "solid law: small-strain linear elasticity (youngs_modulus, poisson_ratio); not "
      "rotation-invariant");
  RegisterIsotropic<CorotationalSolid>(
      registry, "Corotational",
      "solid law: corotational linear elasticity, F = R S (youngs_modulus, poisson_ratio); "
      "handles inverted elements");
  RegisterIsotropic<StVenantKirchhoffSolid>(
      registry, "StVenantKirchhoff",
      "solid law: St Venant-Kirchhoff, S = lambda tr(E) I + 2 mu E (youngs_modulus, "
      "poisson_ratio)");
  RegisterIsotropic<NeoHookeanSolid>(
      registry, "NeoHookean",
      "solid law: compressible neo-Hookean (youngs_modulus, poisson_ratio); needs det F > 0");
  registry.materials.Register(
      "Guccione",
      [](const JsonNode& node) -> std::shared_ptr<const Material> {
        node.CheckKeys({"law", "C", "bf", "bt", "bfs", "bulk_modulus"});
        GuccioneParams params;
        params.C = node.Positive("C");
        params.bf = node.Positive("bf");
        params.bt = node.Positive("bt");
        params.bfs = node.Positive("bfs");
        params.bulk_modulus = node.Positive("bulk_modulus");
        return std::make_shared<GuccioneSolid>(params);
      },
      "solid law: Guccione transversely isotropic exponential myocardium (C, bf, bt, bfs, "
      "bulk_modulus); needs fibres and det F > 0");
}

}  // namespace gipsi
