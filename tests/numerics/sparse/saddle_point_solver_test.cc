// SaddlePointSolver: GMRES with the block-triangular preconditioner, on small saddle points
// against a dense LU, and on MixedSolid's own systems against UMFPACK
// (tests/models/fem/mixed_schur_test.cc).

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include <Eigen/LU>

#include "gipsi/base/error.h"
#include "gipsi/numerics/sparse/saddle_point_solver.h"

namespace gipsi {
namespace {

/// [[K, Bᵀ], [B, −C]] with K a 1-D Laplacian plus `skew` times a nonsymmetric perturbation,
/// B random of full rank, C = c I; and the pressure mass-like Ŝ = I / 2.
struct Saddle {
  SparseMatrix a, schur;
  Index nu = 40, np = 6;
  Saddle(double skew, double c) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(nu + np, nu + np);
    for (Index i = 0; i < nu; ++i) {
      dense(i, i) = 2.5;
      if (i > 0) dense(i, i - 1) = dense(i - 1, i) = -1;
    }
    for (Index i = 1; i < nu; ++i) {
      const double s = skew * u(rng);
      dense(i, i - 1) += s;
      dense(i - 1, i) -= s;
    }
    for (Index p = 0; p < np; ++p)
      for (Index j = 0; j < nu; ++j) {
        const double v = u(rng);
        dense(nu + p, j) = dense(j, nu + p) = v;
      }
    for (Index p = 0; p < np; ++p) dense(nu + p, nu + p) = -c;
    a = dense.sparseView();
    a.makeCompressed();
    Eigen::MatrixXd s = 0.5 * Eigen::MatrixXd::Identity(np, np);
    schur = s.sparseView();
    schur.makeCompressed();
  }
};

// The solution of symmetric and nonsymmetric saddle points (a zero and a nonzero pressure
// block) to the requested tolerance, checked against a dense LU: relative error ≤ 1e-9 with
// a tolerance of 1e-12 (the condition number of these systems is below 1e3).
TEST(SaddlePointSolver, SolvesSymmetricAndNonsymmetricSaddlePointsLikeADenseLu) {
  for (const double skew : {0.0, 0.3})
    for (const double c : {0.0, 0.05}) {
      Saddle s(skew, c);
      LinearSolverOptions options;
      options.type = "schur_gmres";
      options.tolerance = 1e-12;
      SaddlePointSolver solver(s.nu, s.schur, options);
      EXPECT_TRUE(solver.AcceptIndefinite());
      solver.AnalyzePattern(s.a);
      ASSERT_TRUE(solver.Factorize(s.a));
      VecX b = VecX::LinSpaced(s.nu + s.np, -1, 2), x;
      const LinearSolveStats stats = solver.Solve(b, x);
      EXPECT_TRUE(stats.converged) << "skew " << skew << " c " << c;
      EXPECT_LE(stats.relative_residual, 1e-12);
      EXPECT_GT(stats.iterations, 0);
      const VecX exact = Eigen::MatrixXd(s.a).fullPivLu().solve(b);
      EXPECT_LT((x - exact).norm(), 1e-9 * exact.norm()) << "skew " << skew << " c " << c;
      // b = 0 gives 0 at once; a non-finite b does not converge.
      VecX zero = VecX::Zero(b.size()), x0;
      EXPECT_TRUE(solver.Solve(zero, x0).converged);
      EXPECT_EQ(x0.norm(), 0);
      b[3] = std::numeric_limits<double>::quiet_NaN();
      EXPECT_FALSE(solver.Solve(b, x).converged);
    }
}

// A matrix with a non-finite value is refused by Factorize, and Solve then reports failure;
// the generic factory refuses the type (it needs the pressure block's Schur approximation).
TEST(SaddlePointSolver, RefusesNonFiniteMatricesAndTheGenericFactory) {
  Saddle s(0, 0);
  LinearSolverOptions options;
  options.type = "schur_gmres";
  SaddlePointSolver solver(s.nu, s.schur, options);
  solver.AnalyzePattern(s.a);
  SparseMatrix bad = s.a;
  bad.valuePtr()[5] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(solver.Factorize(bad));
  VecX b = VecX::Ones(s.nu + s.np), x;
  EXPECT_FALSE(solver.Solve(b, x).converged);
  try {
    (void)MakeLinearSolver(options);
    ADD_FAILURE() << "MakeLinearSolver took 'schur_gmres'";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "linear solver type 'schur_gmres' solves the saddle points of mixed elements (a "
                 "MixedSolid's); this object's systems are not saddle points");
  }
}

}  // namespace
}  // namespace gipsi
