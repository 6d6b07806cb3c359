// Restarted GMRES against a dense LU solve: a nonsymmetric system (full and restarted Krylov
// spaces), finite termination, a zero right-hand side, and a singular operator reported as
// not converged rather than as an answer.

#include "gipsi/numerics/gmres.h"

#include <gtest/gtest.h>

#include <Eigen/LU>

namespace gipsi {
namespace {

/// I + 0.3 R with R uniform in [−1, 1] / √n (fixed seed): nonsymmetric, eigenvalues within
/// ~0.3 of 1, so GMRES converges geometrically.
Eigen::MatrixXd NearIdentity(Index n) {
  std::srand(7);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Random(n, n) / std::sqrt(double(n));
  return Eigen::MatrixXd::Identity(n, n) + 0.3 * r;
}

GmresResult SolveDense(const Eigen::MatrixXd& a, const VecX& b, VecX& x, GmresOptions options) {
  auto apply = [&](Eigen::Ref<const VecX> in, Eigen::Ref<VecX> out) { out.noalias() = a * in; };
  Gmres gmres;
  gmres.Prepare(a.rows(), options);
  return gmres.Solve(LinearOperatorRef(apply), b, x);
}

TEST(Gmres, SolvesANonsymmetricSystemLikeLu) {
  const Index n = 60;
  const Eigen::MatrixXd a = NearIdentity(n);
  const VecX b = VecX::LinSpaced(n, -1, 2);
  const VecX exact = a.partialPivLu().solve(b);
  for (int restart : {60, 8}) {  // the full space, and restarts every 8 products
    VecX x;
    const GmresResult result = SolveDense(a, b, x, {restart, 500, 1e-12});
    ASSERT_TRUE(result.converged) << "restart " << restart;
    EXPECT_LE(result.relative_residual, 1e-12);
    // ‖x − x*‖ ≤ cond(A) ‖r‖/‖b‖ ‖x*‖, and cond(A) < 10 here.
    EXPECT_LE((x - exact).norm(), 1e-10 * exact.norm()) << "restart " << restart;
    EXPECT_NEAR(((a * x - b).norm() / b.norm()), result.relative_residual, 1e-12);
  }
}

TEST(Gmres, TerminatesWithinTheDimensionOfTheSpace) {
  // A diagonal operator with 5 distinct eigenvalues: its Krylov space has dimension 5, so
  // GMRES (lucky breakdown) is exact after 5 products, plus the one that checks the residual.
  const Index n = 40;
  VecX d(n);
  for (Index i = 0; i < n; ++i) d[i] = 1.0 + double(i % 5);
  const Eigen::MatrixXd a = d.asDiagonal();
  const VecX b = VecX::Ones(n);
  VecX x;
  const GmresResult result = SolveDense(a, b, x, {30, 100, 1e-12});
  ASSERT_TRUE(result.converged);
  EXPECT_LE(result.iterations, 6);
  EXPECT_LE((x - b.cwiseQuotient(d)).lpNorm<Eigen::Infinity>(), 1e-13);
}

TEST(Gmres, AZeroRightHandSideGivesZeroAndASingularOperatorDoesNotConverge) {
  const Index n = 10;
  VecX x = VecX::Ones(n);
  GmresResult result = SolveDense(NearIdentity(n), VecX::Zero(n), x, {});
  EXPECT_TRUE(result.converged);
  EXPECT_EQ(result.iterations, 0);
  EXPECT_EQ(x, VecX::Zero(n));
  // The zero operator: no direction reduces the residual.
  result = SolveDense(Eigen::MatrixXd::Zero(n, n), VecX::Ones(n), x, {5, 50, 1e-8});
  EXPECT_FALSE(result.converged);
  EXPECT_TRUE(x.allFinite());
}

}  // namespace
}  // namespace gipsi
