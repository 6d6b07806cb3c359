#include "gipsi/models/fem/solid_laws.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/base/json_node.h"
#include "gipsi/numerics/simd.h"

namespace gipsi {
namespace {

constexpr double kYoung = 1e4;  // Pa
constexpr double kPoisson = 0.3;
constexpr double kActive = 800;  // Pa, an active tension of the order of the stiffness

/// Guccione parameters of the cardiac mechanics benchmark (Land et al., Proc. R. Soc. A 471,
/// 2015: C = 2 kPa, b_f = 8, b_t = 2, b_fs = 4) with a moderately stiff volumetric penalty.
GuccioneParams BenchmarkGuccione() {
  GuccioneParams p;
  p.C = 2e3;
  p.bf = 8;
  p.bt = 2;
  p.bfs = 4;
  p.bulk_modulus = 5e4;
  return p;
}

std::shared_ptr<const SolidMaterial> MakeLaw(const std::string& name) {
  if (name == "Linear") return std::make_shared<LinearSolid>(kYoung, kPoisson);
  if (name == "Corotational") return std::make_shared<CorotationalSolid>(kYoung, kPoisson);
  if (name == "StVenantKirchhoff") {
    return std::make_shared<StVenantKirchhoffSolid>(kYoung, kPoisson);
  }
  if (name == "NeoHookean") return std::make_shared<NeoHookeanSolid>(kYoung, kPoisson);
  return std::make_shared<GuccioneSolid>(BenchmarkGuccione());
}

const LameParameters kLame = LameFromYoungPoisson(kYoung, kPoisson);

Mat3 RandomMatrix(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Mat3 m;
  for (int i = 0; i < 9; ++i) m.data()[i] = u(rng);
  return m;
}

Mat3 RandomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

/// I + amplitude·(random matrix with entries in [−1, 1]), redrawn until det F > 0.2.
Mat3 RandomF(std::mt19937& rng, double amplitude) {
  for (;;) {
    const Mat3 F = Mat3::Identity() + amplitude * RandomMatrix(rng);
    if (F.determinant() > 0.2) return F;
  }
}

/// Random orthonormal fibre axes with or without active tension.
MaterialPoint RandomPoint(std::mt19937& rng, double active_tension) {
  MaterialPoint mp;
  mp.axes = RandomRotation(rng);
  mp.active_tension = active_tension;
  return mp;
}

Mat3 StressOf(const SolidMaterial& law, const Mat3& F, const MaterialPoint& mp) {
  Mat3 P;
  EXPECT_TRUE(law.Stress(F, mp, P)) << "F =\n" << F;
  return P;
}

// Finite-difference tolerances. Central differences with step h have truncation error
// ~h²/6·|f'''| (≈ 1e-12 relative for these smooth laws, up to ~1e-10 for Guccione's exponential)
// and round-off error ~ε_mach·|f|/h ≈ 1e-16/1e-6 = 1e-10 relative; h = 1e-6 balances the two
// near 1e-10, so a relative tolerance of 1e-6 is safe yet catches any wrong term (a missing or
// mis-indexed term is an O(1) relative error).
constexpr double kH = 1e-6;
constexpr double kFdTolerance = 1e-6;

/// ∂W/∂F by central differences.
Mat3 EnergyGradientFd(const SolidMaterial& law, const Mat3& F, const MaterialPoint& mp) {
  Mat3 grad;
  for (int l = 0; l < 3; ++l) {
    for (int k = 0; k < 3; ++k) {
      Mat3 fp = F, fm = F;
      fp(k, l) += kH;
      fm(k, l) -= kH;
      grad(k, l) = (law.Energy(fp, mp) - law.Energy(fm, mp)) / (2 * kH);
    }
  }
  return grad;
}

/// dP/dF by central differences of Stress, column k + 3l = ∂P/∂F_kl.
Mat9 StressJacobianFd(const SolidMaterial& law, const Mat3& F, const MaterialPoint& mp) {
  Mat9 jac;
  for (int l = 0; l < 3; ++l) {
    for (int k = 0; k < 3; ++k) {
      Mat3 fp = F, fm = F;
      fp(k, l) += kH;
      fm(k, l) -= kH;
      const Mat3 dp = (StressOf(law, fp, mp) - StressOf(law, fm, mp)) / (2 * kH);
      jac.col(k + 3 * l) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(dp.data());
    }
  }
  return jac;
}

/// The sample deformations: near I (|F − I| ~ 1e-2) and far from it (~0.3, stretches of tens of
/// percent), with and without active tension, with random fibre axes.
struct Sample {
  Mat3 F;
  MaterialPoint mp;
};
std::vector<Sample> Samples() {
  std::mt19937 rng(20240611);
  std::vector<Sample> out;
  for (double amplitude : {0.01, 0.3}) {
    for (double ta : {0.0, kActive}) {
      for (int r = 0; r < 3; ++r) out.push_back({RandomF(rng, amplitude), RandomPoint(rng, ta)});
    }
  }
  return out;
}

const std::vector<std::string> kAllLaws = {"Linear", "Corotational", "StVenantKirchhoff",
                                           "NeoHookean", "Guccione"};
const std::vector<std::string> kIsotropicLaws = {"Linear", "Corotational", "StVenantKirchhoff",
                                                 "NeoHookean"};
const std::vector<std::string> kFrameIndifferentLaws = {"Corotational", "StVenantKirchhoff",
                                                        "NeoHookean", "Guccione"};
const std::vector<std::string> kIsotropicNonlinearLaws = {"Corotational", "StVenantKirchhoff",
                                                          "NeoHookean"};

class SolidLaw : public ::testing::TestWithParam<std::string> {
 protected:
  std::shared_ptr<const SolidMaterial> law_ = MakeLaw(GetParam());
};
class FrameIndifferentSolidLaw : public SolidLaw {};
class IsotropicNonlinearSolidLaw : public SolidLaw {};

TEST_P(SolidLaw, ReportsItsRegisteredNameAndFamily) {
  EXPECT_EQ(law_->law(), GetParam());
  EXPECT_EQ(law_->family(), "solid");
  EXPECT_EQ(law_->needs_fibres(), GetParam() == "Guccione");
}

TEST_P(SolidLaw, StressIsCentralDifferenceOfEnergy) {
  for (const Sample& s : Samples()) {
    const Mat3 P = StressOf(*law_, s.F, s.mp);
    const Mat3 fd = EnergyGradientFd(*law_, s.F, s.mp);
    EXPECT_LE((P - fd).norm(), kFdTolerance * P.norm()) << "F =\n"
                                                        << s.F << "\nP =\n"
                                                        << P << "\nFD =\n"
                                                        << fd;
  }
}

TEST_P(SolidLaw, TangentIsCentralDifferenceOfStress) {
  for (const Sample& s : Samples()) {
    Mat3 P;
    Mat9 dPdF;
    ASSERT_TRUE(law_->StressAndTangent(s.F, s.mp, P, dPdF));
    const Mat9 fd = StressJacobianFd(*law_, s.F, s.mp);
    EXPECT_LE((dPdF - fd).norm(), kFdTolerance * dPdF.norm()) << "F =\n"
                                                              << s.F << "\ndPdF =\n"
                                                              << dPdF << "\nFD =\n"
                                                              << fd;
  }
}

TEST_P(SolidLaw, TangentIsSymmetricAsTheHessianOfTheEnergy) {
  for (const Sample& s : Samples()) {
    Mat3 P;
    Mat9 dPdF;
    ASSERT_TRUE(law_->StressAndTangent(s.F, s.mp, P, dPdF));
    EXPECT_LE((dPdF - dPdF.transpose()).norm(), 1e-12 * dPdF.norm());
  }
}

TEST_P(SolidLaw, StressAndTangentGivesTheSameStressAsStress) {
  for (const Sample& s : Samples()) {
    Mat3 P;
    Mat9 dPdF;
    ASSERT_TRUE(law_->StressAndTangent(s.F, s.mp, P, dPdF));
    EXPECT_LE((P - StressOf(*law_, s.F, s.mp)).norm(), 1e-12 * P.norm());
  }
}

TEST_P(SolidLaw, IsStressAndEnergyFreeAtIdentityWithoutActiveTension) {
  std::mt19937 rng(1);
  const MaterialPoint mp = RandomPoint(rng, 0);
  const Mat3 P = StressOf(*law_, Mat3::Identity(), mp);
  EXPECT_LE(P.norm(), 1e-12 * kYoung);
  EXPECT_NEAR(law_->Energy(Mat3::Identity(), mp), 0, 1e-12 * kYoung);
}

TEST_P(SolidLaw, ActiveTensionAtIdentityGivesTaFibreFibre) {
  std::mt19937 rng(2);
  const MaterialPoint mp = RandomPoint(rng, kActive);
  const Vec3 f = mp.axes.col(0);
  const Mat3 expected = kActive * f * f.transpose();
  EXPECT_LE((StressOf(*law_, Mat3::Identity(), mp) - expected).norm(), 1e-12 * kActive);
  Mat3 P;
  Mat9 dPdF;
  ASSERT_TRUE(law_->StressAndTangent(Mat3::Identity(), mp, P, dPdF));
  EXPECT_LE((P - expected).norm(), 1e-12 * kActive);
}

/// Closed-form P and W for the confined uniaxial stretch F = diag(stretch, 1, 1), fibre e_x,
/// sheet e_y, active tension `ta` (adding Ta·stretch to P11 and Ta (stretch² − 1)/2 to W).
void ExpectConfinedUniaxial(const SolidMaterial& law, const std::string& name, double stretch,
                            double ta) {
  const double lambda = kLame.lambda, mu = kLame.mu;
  const double e11 = 0.5 * (stretch * stretch - 1);  // Green strain
  const double ln = std::log(stretch);
  double p11 = 0, p22 = 0, w = 0;
  if (name == "Linear" || name == "Corotational") {  // R = I: both are Hooke's law in F − I
    const double eps = stretch - 1;
    p11 = (lambda + 2 * mu) * eps;
    p22 = lambda * eps;
    w = 0.5 * (lambda + 2 * mu) * eps * eps;
  } else if (name == "StVenantKirchhoff") {
    p11 = stretch * (lambda + 2 * mu) * e11;  // P = F S, S11 = (λ + 2μ) E11
    p22 = lambda * e11;
    w = 0.5 * (lambda + 2 * mu) * e11 * e11;
  } else if (name == "NeoHookean") {
    p11 = mu * (stretch - 1 / stretch) + lambda * ln / stretch;
    p22 = lambda * ln;
    w = 0.5 * mu * (stretch * stretch - 1) - mu * ln + 0.5 * lambda * ln * ln;
  } else {  // Guccione, fibre along the stretch: Q = b_f E11²
    const GuccioneParams g = BenchmarkGuccione();
    const double q = g.bf * e11 * e11;
    p11 = stretch * g.C * std::exp(q) * g.bf * e11 + g.bulk_modulus * ln / stretch;
    p22 = g.bulk_modulus * ln;
    w = 0.5 * g.C * (std::exp(q) - 1) + 0.5 * g.bulk_modulus * ln * ln;
  }
  p11 += ta * stretch;
  w += ta * e11;
  MaterialPoint mp;
  mp.active_tension = ta;
  const Mat3 F = Vec3(stretch, 1, 1).asDiagonal();
  const Mat3 expected = Vec3(p11, p22, p22).asDiagonal();
  const Mat3 P = StressOf(law, F, mp);
  EXPECT_LE((P - expected).norm(), 1e-12 * expected.norm())
      << name << " stretch " << stretch << "\nP =\n"
      << P << "\nexpected\n"
      << expected;
  EXPECT_NEAR(law.Energy(F, mp), w, 1e-12 * std::abs(w));
}

TEST_P(SolidLaw, ConfinedUniaxialStretchMatchesClosedForm) {
  for (double stretch : {0.8, 1.05, 1.3}) {
    for (double ta : {0.0, kActive}) ExpectConfinedUniaxial(*law_, GetParam(), stretch, ta);
  }
}

TEST_P(FrameIndifferentSolidLaw, RigidRotationIsStressFree) {
  std::mt19937 rng(3);
  for (int r = 0; r < 5; ++r) {
    const Mat3 R = RandomRotation(rng);
    const MaterialPoint mp = RandomPoint(rng, 0);
    EXPECT_LE(StressOf(*law_, R, mp).norm(), 1e-11 * kYoung) << "R =\n" << R;
    EXPECT_NEAR(law_->Energy(R, mp), 0, 1e-11 * kYoung);
  }
}

TEST_P(FrameIndifferentSolidLaw, IsFrameIndifferent) {
  std::mt19937 rng(4);
  for (const Sample& s : Samples()) {
    const Mat3 Q = RandomRotation(rng);
    const Mat3 P = StressOf(*law_, s.F, s.mp);
    const Mat3 PQ = StressOf(*law_, Q * s.F, s.mp);
    EXPECT_LE((PQ - Q * P).norm(), 1e-12 * P.norm());  // P(QF) = Q P(F)
    const double w = law_->Energy(s.F, s.mp);
    EXPECT_NEAR(law_->Energy(Q * s.F, s.mp), w, 1e-12 * std::abs(w) + 1e-12 * kYoung);
  }
}

/// ‖P_law(I + εH) − P_linear(I + εH)‖ for a fixed random direction H.
double DistanceFromLinear(const SolidMaterial& law, const Mat3& H, double eps) {
  const LinearSolid linear(kYoung, kPoisson);
  const Mat3 F = Mat3::Identity() + eps * H;
  return (StressOf(law, F, {}) - StressOf(linear, F, {})).norm();
}

TEST_P(IsotropicNonlinearSolidLaw, SmallStrainStressAgreesWithLinearToSecondOrder) {
  std::mt19937 rng(5);
  const Mat3 H = RandomMatrix(rng);
  // At ε = 1e-7 the stresses agree to relative O(ε) (plus round-off ≲ 1e-8 relative, from
  // F − F⁻ᵀ-type cancellations), while any first-order discrepancy would be O(1) relative.
  const double eps = 1e-7;
  const double linear_norm =
      StressOf(LinearSolid(kYoung, kPoisson), Mat3::Identity() + eps * H, {}).norm();
  EXPECT_LE(DistanceFromLinear(*law_, H, eps), 1e-5 * linear_norm);
  // The difference is O(ε²): a tenfold smaller ε shrinks it about a hundredfold.
  const double ratio = DistanceFromLinear(*law_, H, 1e-2) / DistanceFromLinear(*law_, H, 1e-3);
  EXPECT_GT(ratio, 50);
  EXPECT_LT(ratio, 200);
}

INSTANTIATE_TEST_SUITE_P(AllLaws, SolidLaw, ::testing::ValuesIn(kAllLaws));
INSTANTIATE_TEST_SUITE_P(FrameIndifferentLaws, FrameIndifferentSolidLaw,
                         ::testing::ValuesIn(kFrameIndifferentLaws));
INSTANTIATE_TEST_SUITE_P(IsotropicNonlinearLaws, IsotropicNonlinearSolidLaw,
                         ::testing::ValuesIn(kIsotropicNonlinearLaws));

TEST(LinearLaw, RigidRotationProducesSpuriousStress) {
  const LinearSolid law(kYoung, kPoisson);
  const Mat3 R = Eigen::AngleAxisd(0.5, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  EXPECT_GT(StressOf(law, R, {}).norm(), 0.05 * kYoung);
  EXPECT_GT(law.Energy(R, {}), 1e-3 * kYoung);
}

TEST(LinearLaw, ReportsItsYoungsModulusAndPoissonRatio) {
  const LinearSolid law(kYoung, kPoisson);
  EXPECT_EQ(law.small_strain_youngs_modulus(), kYoung);
  EXPECT_EQ(law.small_strain_poisson_ratio(), kPoisson);
  EXPECT_DOUBLE_EQ(law.mu(), kYoung / 2.6);
  EXPECT_DOUBLE_EQ(law.lambda(), kYoung * 0.3 / (1.3 * 0.4));
}

/// An inverted deformation with distinct singular magnitudes (det F < 0).
Mat3 InvertedF() {
  const Mat3 Q1 = Eigen::AngleAxisd(0.4, Vec3(1, -1, 2).normalized()).toRotationMatrix();
  const Mat3 Q2 = Eigen::AngleAxisd(-0.7, Vec3(0, 1, 1).normalized()).toRotationMatrix();
  return Q1 * Vec3(1.2, 0.9, -0.4).asDiagonal() * Q2;
}

TEST(CorotationalLaw, SignedSvdGivesProperRotationsForInvertedF) {
  const Mat3 F = InvertedF();
  Mat3 U, V;
  Vec3 sigma;
  SignedSvd(F, U, sigma, V);
  EXPECT_NEAR(U.determinant(), 1, 1e-14);
  EXPECT_NEAR(V.determinant(), 1, 1e-14);
  EXPECT_LE((U * sigma.asDiagonal() * V.transpose() - F).norm(), 1e-14);
  EXPECT_NEAR(sigma(0), 1.2, 1e-14);
  EXPECT_NEAR(sigma(1), 0.9, 1e-14);
  EXPECT_NEAR(sigma(2), -0.4, 1e-14);  // the reflection sits on the smallest singular value
}

TEST(CorotationalLaw, InvertedElementHasFiniteStressAndMatchingTangent) {
  const CorotationalSolid law(kYoung, kPoisson);
  const Mat3 F = InvertedF();
  MaterialPoint mp;
  Mat3 P;
  Mat9 dPdF;
  ASSERT_TRUE(law.StressAndTangent(F, mp, P, dPdF));
  EXPECT_TRUE(P.allFinite() && dPdF.allFinite());
  EXPECT_TRUE(std::isfinite(law.Energy(F, mp)));
  EXPECT_LE((P - EnergyGradientFd(law, F, mp)).norm(), kFdTolerance * P.norm());
  EXPECT_LE((dPdF - StressJacobianFd(law, F, mp)).norm(), kFdTolerance * dPdF.norm());
  // The stress drives the element back towards a positive volume: a small descent step along
  // −P raises det F.
  const Mat3 descended = F - 1e-3 * P / P.norm();
  EXPECT_LT(law.Energy(descended, mp), law.Energy(F, mp));
  EXPECT_GT(descended.determinant(), F.determinant());
}

TEST(CorotationalLaw, TangentStaysFiniteWhereTheRotationIsNotDifferentiable) {
  // σ₂ + σ₃ = 0 (inverted) and a flat element: tr(S) I − S is singular, the clamp keeps the
  // tangent finite.
  const CorotationalSolid law(kYoung, kPoisson);
  for (const Vec3& sv : {Vec3(1.0, 0.5, -0.5), Vec3(1.0, 0.0, 0.0)}) {
    const Mat3 F = sv.asDiagonal();
    Mat3 P;
    Mat9 dPdF;
    ASSERT_TRUE(law.StressAndTangent(F, {}, P, dPdF)) << sv.transpose();
    EXPECT_TRUE(P.allFinite() && dPdF.allFinite()) << sv.transpose();
  }
}

/// A rest tetrahedron (edges X1 − X0, X2 − X0, X3 − X0 of a skewed tet): its shape gradients and
/// volume.
void RestTet(TetGradients& g, double& volume) {
  Mat3 X;
  X << 0.10, 0.02, -0.01, 0.00, 0.08, 0.03, 0.01, -0.02, 0.12;
  const Mat3 inverse = X.inverse();
  for (int a = 0; a < 3; ++a) g.col(a + 1) = inverse.row(a).transpose();
  g.col(0) = -(g.col(1) + g.col(2) + g.col(3));
  volume = X.determinant() / 6;
}

// A law's closed-form element stiffness is the generic contraction of its (finite-difference
// checked) 9×9 tangent: a large rotated deformation and `second_F`, each with and without an
// active tension along an oblique fibre (also the law's fibre frame). Both are sums of a few
// dozen products of O(1) factors times the stiffness, so they agree to ~1e-15 relative; 1e-12
// leaves room for the different association of the sums.
void ExpectClosedFormMatchesContraction(const SolidMaterial& law, const Mat3& second_F) {
  TetGradients g;
  double volume = 0;
  RestTet(g, volume);
  Mat3 large;
  large << 1.2, 0.15, 0.0, -0.1, 0.9, 0.2, 0.05, 0.0, 1.1;
  const Mat3 rotation = Eigen::AngleAxisd(0.8, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
  for (const Mat3& F : {Mat3(rotation * large), second_F}) {
    for (double active : {0.0, kActive}) {
      MaterialPoint mp;
      mp.axes = Eigen::AngleAxisd(0.4, Vec3(0, 1, 1).normalized()).toRotationMatrix();
      mp.active_tension = active;
      Mat3 p_fast, p_generic;
      Mat12 k_fast, k_generic;
      ASSERT_TRUE(law.ElementStressAndStiffness(F, mp, g, volume, p_fast, k_fast));
      ASSERT_TRUE(
          law.SolidMaterial::ElementStressAndStiffness(F, mp, g, volume, p_generic, k_generic));
      EXPECT_LE((p_fast - p_generic).norm(), 1e-12 * p_generic.norm()) << "active " << active;
      EXPECT_LE((k_fast - k_generic).norm(), 1e-12 * k_generic.norm()) << "active " << active;
      EXPECT_LE((k_fast - k_fast.transpose()).norm(), 1e-12 * k_fast.norm());
    }
  }
}

/// The closed form refuses an inverted element, as the law's tangent does.
void ExpectInvertedElementRefused(const SolidMaterial& law) {
  TetGradients g;
  double volume = 0;
  RestTet(g, volume);
  Mat3 P;
  Mat12 K;
  EXPECT_FALSE(law.ElementStressAndStiffness(InvertedF(), {}, g, volume, P, K));
}

// The corotational closed form on the fast polar path and, for an inverted element, on the SVD
// path.
TEST(CorotationalLaw, ClosedFormElementStiffnessMatchesTheContractedTangent) {
  ExpectClosedFormMatchesContraction(CorotationalSolid(kYoung, kPoisson), InvertedF());
}

// A law's batched kernel (four elements in vector lanes) against its element-wise closed form,
// lane by lane: large rotations and stretches on the vector path; an inverted, a non-finite
// and an actively tensed element that the batch hands to the element-wise path; batches of 1 to
// 4 elements. The same formula evaluated in another association (its own 3×3 inverses and
// products), so agreement to 1e-12 relative, as above; the AVX and generic kernels give the
// same bits.
void ExpectBatchMatchesElementWise(const SolidMaterial& law) {
  std::mt19937 engine(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  auto random_tet = [&](TetGradients& g, double& volume) {
    Mat3 X;
    do {
      X = 0.1 * Mat3::Identity();
      for (int k = 0; k < 9; ++k) X.data()[k] += 0.03 * uniform(engine);
    } while (X.determinant() <= 1e-5);
    const Mat3 inverse = X.inverse();
    for (int a = 0; a < 3; ++a) g.col(a + 1) = inverse.row(a).transpose();
    g.col(0) = -(g.col(1) + g.col(2) + g.col(3));
    volume = X.determinant() / 6;
  };
  auto random_f = [&] {
    Mat3 stretch = Mat3::Identity();
    for (int k = 0; k < 9; ++k) stretch.data()[k] += 0.3 * uniform(engine);
    const Vec3 axis = Vec3(uniform(engine), uniform(engine), uniform(engine)).normalized();
    return Mat3(Eigen::AngleAxisd(3.0 * uniform(engine), axis).toRotationMatrix() * stretch);
  };
  MaterialPoint tensed;
  tensed.axes = Eigen::AngleAxisd(0.4, Vec3(0, 1, 1).normalized()).toRotationMatrix();
  tensed.active_tension = kActive;
  const Mat3 not_finite = Mat3::Constant(std::numeric_limits<double>::quiet_NaN());
  int vector_lanes = 0;
  for (int trial = 0; trial < 40; ++trial) {
    ElementBatch batch, generic;
    batch.count = 1 + trial % ElementBatch::kLanes;
    for (int l = 0; l < batch.count; ++l) {
      TetGradients g;
      double volume = 0;
      random_tet(g, volume);
      Mat3 F = random_f();
      MaterialPoint mp;
      const int kind = (trial + 3 * l) % 7;  // every fifth to seventh lane left to the element path
      if (kind == 4) F = InvertedF();
      if (kind == 5) F = not_finite;
      if (kind == 6) mp = tensed;
      vector_lanes += kind < 4 ? 1 : 0;
      batch.SetInput(l, F, g, volume, mp);
    }
    generic = batch;
    law.ElementStressAndStiffnessBatch(batch);
    const SimdKernels before = LimitSimdKernels(SimdKernels::kGeneric);
    law.ElementStressAndStiffnessBatch(generic);
    LimitSimdKernels(before);
    for (int l = 0; l < batch.count; ++l) {
      Mat3 P;
      Mat12 K;
      const bool ok = law.ElementStressAndStiffness(batch.InputF(l), batch.mp[l],
                                                    batch.InputGradients(l), batch.volume[l], P, K);
      ASSERT_EQ(batch.ok[l], ok) << "trial " << trial << " lane " << l;
      ASSERT_EQ(generic.ok[l], ok);
      if (!ok) continue;
      EXPECT_LE((batch.OutputP(l) - P).norm(), 1e-12 * P.norm())
          << "trial " << trial << " lane " << l;
      EXPECT_LE((batch.OutputK(l) - K).norm(), 1e-12 * K.norm())
          << "trial " << trial << " lane " << l;
      for (int k = 0; k < 9; ++k)
        EXPECT_EQ(std::memcmp(&batch.P[k][l], &generic.P[k][l], sizeof(double)), 0);
      for (int k = 0; k < 144; ++k)
        EXPECT_EQ(std::memcmp(&batch.K[k][l], &generic.K[k][l], sizeof(double)), 0);
    }
  }
  EXPECT_GE(vector_lanes, 40);  // most lanes took the vector path
}

TEST(CorotationalLaw, BatchedLanesMatchTheElementWiseStiffness) {
  const CorotationalSolid law(kYoung, kPoisson);
  ASSERT_TRUE(law.has_batch_kernel());
  ExpectBatchMatchesElementWise(law);
}

TEST(GuccioneLaw, BatchedLanesMatchTheElementWiseStiffness) {
  const GuccioneSolid law(BenchmarkGuccione());
  ASSERT_TRUE(law.has_batch_kernel());
  ExpectBatchMatchesElementWise(law);  // its lanes take the actively tensed elements too
}

TEST(NeoHookeanLaw, BatchedLanesMatchTheElementWiseStiffness) {
  const NeoHookeanSolid law(kYoung, kPoisson);
  ASSERT_TRUE(law.has_batch_kernel());
  ExpectBatchMatchesElementWise(law);
}

TEST(NeoHookeanLaw, ClosedFormElementStiffnessMatchesTheContractedTangent) {
  Mat3 compressed;
  compressed << 0.9, 0.1, 0.0, 0.0, 0.8, -0.05, 0.02, 0.0, 1.05;
  ExpectClosedFormMatchesContraction(NeoHookeanSolid(kYoung, kPoisson), compressed);
  ExpectInvertedElementRefused(NeoHookeanSolid(kYoung, kPoisson));
}

TEST(GuccioneLaw, ClosedFormElementStiffnessMatchesTheContractedTangent) {
  Mat3 compressed;
  compressed << 0.9, 0.1, 0.0, 0.0, 0.8, -0.05, 0.02, 0.0, 1.05;
  ExpectClosedFormMatchesContraction(GuccioneSolid(BenchmarkGuccione()), compressed);
  ExpectInvertedElementRefused(GuccioneSolid(BenchmarkGuccione()));
}

/// Inverted, flat and non-finite deformations.
std::vector<Mat3> OutsideDomain() {
  return {InvertedF(), Vec3(1, 1, 0).asDiagonal(), Vec3(1, 1, 1e-13).asDiagonal(),
          Mat3::Constant(std::numeric_limits<double>::quiet_NaN())};
}

void ExpectOutsideDomain(const SolidMaterial& law) {
  for (const Mat3& F : OutsideDomain()) {
    Mat3 P;
    Mat9 dPdF;
    EXPECT_FALSE(law.Stress(F, {}, P)) << "F =\n" << F;
    EXPECT_FALSE(law.StressAndTangent(F, {}, P, dPdF)) << "F =\n" << F;
    EXPECT_EQ(law.Energy(F, {}), std::numeric_limits<double>::infinity()) << "F =\n" << F;
  }
}

TEST(NeoHookeanLaw, InvertedOrFlatElementIsOutsideTheDomain) {
  ExpectOutsideDomain(NeoHookeanSolid(kYoung, kPoisson));
}

TEST(GuccioneLaw, InvertedOrFlatElementIsOutsideTheDomain) {
  ExpectOutsideDomain(GuccioneSolid(BenchmarkGuccione()));
}

TEST(GuccioneLaw, CrossFibreUniaxialStretchUsesTransverseExponent) {
  const GuccioneParams g = BenchmarkGuccione();
  const GuccioneSolid law(g);
  MaterialPoint mp;  // fibre e_y, sheet e_z, normal e_x: the stretch is along the normal
  mp.axes.col(0) = Vec3::UnitY();
  mp.axes.col(1) = Vec3::UnitZ();
  mp.axes.col(2) = Vec3::UnitX();
  for (double stretch : {0.85, 1.2}) {
    const double e = 0.5 * (stretch * stretch - 1);
    const double ln = std::log(stretch);
    const double q = g.bt * e * e;
    const double p11 = stretch * g.C * std::exp(q) * g.bt * e + g.bulk_modulus * ln / stretch;
    const double p22 = g.bulk_modulus * ln;
    const Mat3 expected = Vec3(p11, p22, p22).asDiagonal();
    const Mat3 P = StressOf(law, Vec3(stretch, 1, 1).asDiagonal(), mp);
    EXPECT_LE((P - expected).norm(), 1e-12 * expected.norm()) << P;
  }
}

TEST(GuccioneLaw, FibreIsStifferThanCrossFibreWhenBfExceedsBt) {
  const GuccioneSolid law(BenchmarkGuccione());
  MaterialPoint along, across;
  across.axes.col(0) = Vec3::UnitY();
  across.axes.col(1) = Vec3::UnitZ();
  across.axes.col(2) = Vec3::UnitX();
  const double stretch = 1.1;
  const Mat3 F = Vec3(stretch, 1, 1).asDiagonal();
  const double p_along = StressOf(law, F, along)(0, 0);
  const double p_across = StressOf(law, F, across)(0, 0);
  EXPECT_GT(p_along, p_across);
  // Beyond the shared volumetric part κ ln λ / λ, the fibre response is at least b_f / b_t = 4
  // times the cross-fibre one (the exponential adds to that).
  const double p_volumetric = BenchmarkGuccione().bulk_modulus * std::log(stretch) / stretch;
  EXPECT_GT(p_along - p_volumetric, 4 * (p_across - p_volumetric));
}

TEST(GuccioneLaw, ExponentOverflowIsReportedNeverReturnedAsInfiniteStress) {
  const GuccioneSolid law(BenchmarkGuccione());
  for (double stretch = 1.0; stretch < 20; stretch *= 1.05) {
    const Mat3 F = Vec3(stretch, 1, 1).asDiagonal();
    Mat3 P;
    Mat9 dPdF;
    if (law.Stress(F, {}, P)) {
      EXPECT_TRUE(P.allFinite()) << stretch;
      EXPECT_TRUE(std::isfinite(law.Energy(F, {}))) << stretch;
    }
    if (law.StressAndTangent(F, {}, P, dPdF)) {
      EXPECT_TRUE(P.allFinite() && dPdF.allFinite()) << stretch;
    }
  }
  // Q = b_f E11² = 8 (99/2)² ≫ 700: beyond the guard.
  const Mat3 F = Vec3(10, 1, 1).asDiagonal();
  Mat3 P;
  EXPECT_FALSE(law.Stress(F, {}, P));
  EXPECT_EQ(law.Energy(F, {}), std::numeric_limits<double>::infinity());
}

/// Checks small_strain_youngs_modulus/poisson_ratio against the tangent at F = I (fibre e_x):
/// normal stiffness K_ab = ∂P_aa/∂F_bb, unconfined uniaxial moduli 1 / (K⁻¹)_aa, bulk modulus
/// Σ K_ab / 9 (a hydrostatic strain e I gives a mean stress K·3e).
void ExpectSmallStrainModuliFromTangent(const GuccioneParams& params, bool fibre_is_stiffest) {
  const GuccioneSolid law(params);
  Mat3 P;
  Mat9 dPdF;
  ASSERT_TRUE(law.StressAndTangent(Mat3::Identity(), {}, P, dPdF));
  Mat3 K;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) K(a, b) = dPdF(a + 3 * a, b + 3 * b);
  }
  const Mat3 compliance = K.inverse();
  const double e_fibre = 1 / compliance(0, 0);
  const double e_cross = 1 / compliance(1, 1);
  EXPECT_EQ(e_fibre > e_cross, fibre_is_stiffest);
  const double e = std::max(e_fibre, e_cross);
  EXPECT_NEAR(law.small_strain_youngs_modulus(), e, 1e-10 * e);
  const double bulk = K.sum() / 9;
  EXPECT_NEAR(law.small_strain_poisson_ratio(), (3 * bulk - e) / (6 * bulk), 1e-10);
}

TEST(GuccioneLaw, SmallStrainModuliMatchTheLinearisedTangent) {
  ExpectSmallStrainModuliFromTangent(BenchmarkGuccione(), true);
  GuccioneParams stiff_across = BenchmarkGuccione();
  stiff_across.bf = 1;
  stiff_across.bt = 6;
  ExpectSmallStrainModuliFromTangent(stiff_across, false);
  const GuccioneSolid law(BenchmarkGuccione());
  EXPECT_GT(law.small_strain_poisson_ratio(), 0.4);  // κ ≫ C: nearly incompressible
  EXPECT_LT(law.small_strain_poisson_ratio(), 0.5);
}

// ---------------------------------------------------------------------------------------------
// JSON factories

std::shared_ptr<const SolidMaterial> Build(const std::string& material_json) {
  TypeRegistry registry;
  RegisterSolidLaws(registry);
  const JsonDocument doc =
      JsonDocument::Parse("{\"material\": " + material_json + "}", "scene.json");
  return registry.CreateMaterialAs<SolidMaterial>(doc.root().At("material"), "solid");
}

/// The InputError message for building `material_json` (fails the test if none is thrown).
std::string ErrorOf(const std::string& material_json) {
  try {
    (void)Build(material_json);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError for " << material_json;
  return "";
}

TEST(SolidLawJson, BuildsEveryLawFromGoodParameters) {
  for (const std::string& name : kIsotropicLaws) {
    const auto law =
        Build(R"({"law": ")" + name + R"(", "youngs_modulus": 2.5e4, "poisson_ratio": 0.45})");
    ASSERT_NE(law, nullptr);
    EXPECT_EQ(law->law(), name);
    EXPECT_EQ(law->small_strain_youngs_modulus(), 2.5e4);
    EXPECT_EQ(law->small_strain_poisson_ratio(), 0.45);
  }
  const auto guccione =
      Build(R"({"law": "Guccione", "C": 2000, "bf": 8, "bt": 2, "bfs": 4, "bulk_modulus": 5e4})");
  ASSERT_NE(guccione, nullptr);
  EXPECT_EQ(guccione->law(), "Guccione");
  EXPECT_TRUE(guccione->needs_fibres());
  const auto* typed = dynamic_cast<const GuccioneSolid*>(guccione.get());
  ASSERT_NE(typed, nullptr);
  EXPECT_EQ(typed->params().bfs, 4);
  EXPECT_EQ(typed->params().bulk_modulus, 5e4);
}

TEST(SolidLawJson, RejectsNegativeYoungsModulusNamingThePath) {
  const std::string msg =
      ErrorOf(R"({"law": "NeoHookean", "youngs_modulus": -1e4, "poisson_ratio": 0.3})");
  EXPECT_NE(msg.find("scene.json"), std::string::npos) << msg;
  EXPECT_NE(msg.find("material.youngs_modulus"), std::string::npos) << msg;
}

TEST(SolidLawJson, RejectsIncompressiblePoissonRatioSuggestingANearValue) {
  const std::string msg =
      ErrorOf(R"({"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.5})");
  EXPECT_NE(msg.find("material.poisson_ratio"), std::string::npos) << msg;
  EXPECT_NE(msg.find("0.49"), std::string::npos) << msg;
}

TEST(SolidLawJson, RejectsPoissonRatioAtOrBelowMinusOne) {
  const std::string msg =
      ErrorOf(R"({"law": "Corotational", "youngs_modulus": 1e4, "poisson_ratio": -1})");
  EXPECT_NE(msg.find("material.poisson_ratio"), std::string::npos) << msg;
}

TEST(SolidLawJson, RejectsGuccioneWithoutC) {
  const std::string msg =
      ErrorOf(R"({"law": "Guccione", "bf": 8, "bt": 2, "bfs": 4, "bulk_modulus": 5e4})");
  EXPECT_NE(msg.find("material"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'C'"), std::string::npos) << msg;
}

TEST(SolidLawJson, RejectsNonPositiveGuccioneExponentNamingThePath) {
  const std::string msg =
      ErrorOf(R"({"law": "Guccione", "C": 2000, "bf": 0, "bt": 2, "bfs": 4, "bulk_modulus": 5e4})");
  EXPECT_NE(msg.find("material.bf"), std::string::npos) << msg;
}

TEST(SolidLawJson, RejectsUnknownKeySuggestingTheClosest) {
  const std::string msg =
      ErrorOf(R"({"law": "StVenantKirchhoff", "youngs_modulos": 1e4, "poisson_ratio": 0.3})");
  EXPECT_NE(msg.find("material"), std::string::npos) << msg;
  EXPECT_NE(msg.find("youngs_modulos"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean 'youngs_modulus'"), std::string::npos) << msg;
}

TEST(SolidLawJson, RejectsSolidLawWhereAnotherFamilyIsNeeded) {
  TypeRegistry registry;
  RegisterSolidLaws(registry);
  const JsonDocument doc = JsonDocument::Parse(
      R"({"material": {"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.3}})",
      "scene.json");
  try {
    (void)registry.CreateMaterial(doc.root().At("material"), "spring");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("material.law"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace gipsi
