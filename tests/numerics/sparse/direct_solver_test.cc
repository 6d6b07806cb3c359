// Direct solvers (Eigen SimplicialLDLT, CHOLMOD supernodal LLᵀ): SPD checks, indefinite matrices
// once accepted, recovery after a failed factorisation, reuse of the symbolic analysis, and their
// stats.

#include <string>

#include <gtest/gtest.h>

#include "gipsi/numerics/sparse/linear_solver.h"
#include "gipsi/numerics/sparse/serial_openmp.h"
#include "numerics/sparse/sparse_test_util.h"

namespace gipsi {
namespace {

using testing::IndependentRelativeResidual;
using testing::Manufacture;

class DirectSparseSolver : public ::testing::TestWithParam<std::string> {
 protected:
  std::unique_ptr<LinearSolver> MakeSolver() const {
    LinearSolverOptions options;
    options.type = GetParam();
    return MakeLinearSolver(options);
  }
};

// Shift −1 puts eigenvalues of the 10³ Laplacian on both sides of 0: no Cholesky exists, and
// an LDLᵀ has a negative pivot. Factorize must say so (no crash, no exception, no output).
TEST_P(DirectSparseSolver, IndefiniteMatrixFailsFactorizeWithoutCrashing) {
  const SparseMatrix A = MakeLaplacian3D(10, -1.0);
  auto solver = MakeSolver();
  solver->AnalyzePattern(A);
  EXPECT_FALSE(solver->Factorize(A));
  VecX x = VecX::Zero(A.rows());
  const LinearSolveStats stats = solver->Solve(VecX::Ones(A.rows()), x);
  EXPECT_FALSE(stats.converged);
}

TEST_P(DirectSparseSolver, NegativeDefiniteMatrixFailsFactorize) {
  const SparseMatrix A = -MakeLaplacian3D(6, 0.5);
  auto solver = MakeSolver();
  solver->AnalyzePattern(A);
  EXPECT_FALSE(solver->Factorize(A));
}

TEST_P(DirectSparseSolver, RecoversAfterAFailedFactorization) {
  const SparseMatrix bad = MakeLaplacian3D(10, -1.0);
  const SparseMatrix good = MakeLaplacian3D(10, 0.2);
  auto solver = MakeSolver();
  solver->AnalyzePattern(good);
  ASSERT_FALSE(solver->Factorize(bad));
  ASSERT_TRUE(solver->Factorize(good));
  const auto problem = Manufacture(good);
  VecX x;
  const LinearSolveStats stats = solver->Solve(problem.b, x);
  EXPECT_TRUE(stats.converged);
  EXPECT_LE(IndependentRelativeResidual(good, problem.b, x), 1e-12);
}

// After AcceptIndefinite (the pressure-loaded solids' tangents), both solve the indefinite
// shifted Laplacian to round-off; "cholmod" falls back from its LLᵀ to LDLᵀ for it and goes back
// to LLᵀ for the next, definite matrix of the pattern. Bound 1e-10: the shifted matrix's
// condition number is about 1e2, so round-off leaves residuals near 1e-14.
TEST_P(DirectSparseSolver, AfterAcceptIndefiniteSolvesIndefiniteAndDefiniteMatrices) {
  const SparseMatrix indefinite = MakeLaplacian3D(10, -1.0);
  const SparseMatrix definite = MakeLaplacian3D(10, 0.2);
  auto solver = MakeSolver();
  ASSERT_TRUE(solver->AcceptIndefinite());
  solver->AnalyzePattern(definite);
  for (const SparseMatrix* A : {&indefinite, &definite, &indefinite}) {
    ASSERT_TRUE(solver->Factorize(*A));
    const auto problem = Manufacture(*A);
    VecX x;
    const LinearSolveStats stats = solver->Solve(problem.b, x);
    EXPECT_TRUE(stats.converged);
    EXPECT_LE(IndependentRelativeResidual(*A, problem.b, x), 1e-10);
  }
}

// One AnalyzePattern, then several matrices of that pattern: each Factorize is numeric only
// (reported as refactorized), and each solve is to round-off.
TEST_P(DirectSparseSolver, ReusesOneAnalysisForManyMatricesOfThePattern) {
  auto solver = MakeSolver();
  solver->AnalyzePattern(testing::TestLattice());
  for (double scale : {1.0, 3.0, 0.1}) {
    const SparseMatrix A = testing::TestLattice(scale);
    ASSERT_TRUE(solver->Factorize(A));
    const auto problem = Manufacture(A, 21);
    VecX x = testing::RandomVector(A.rows(), 5);  // ignored
    const LinearSolveStats stats = solver->Solve(problem.b, x);
    EXPECT_TRUE(stats.converged);
    EXPECT_TRUE(stats.refactorized);
    EXPECT_EQ(stats.iterations, 0);
    EXPECT_LE(stats.relative_residual, 1e-12);
    EXPECT_LE((x - problem.x_true).norm(), 1e-6 * problem.x_true.norm()) << "scale " << scale;
  }
}

INSTANTIATE_TEST_SUITE_P(LdltAndCholmod, DirectSparseSolver, ::testing::Values("ldlt", "cholmod"));

}  // namespace
}  // namespace gipsi

namespace gipsi {
namespace {

TEST(SerialOpenMp, RegionsInsideRunOnOneThreadAndTheSettingIsRestored) {
  // CHOLMOD's regions ask for a fixed team of four (num_threads(4)); inside the guard such a
  // region must get one thread, and GiPSi's own regions their usual team after it.
  const int levels = omp_get_max_active_levels();
  int inside = 0, after = 0;
  {
    const SerialOpenMp serial;
#pragma omp parallel num_threads(4)
    {
#pragma omp single
      inside = omp_get_num_threads();
    }
  }
#pragma omp parallel num_threads(2)
  {
#pragma omp single
    after = omp_get_num_threads();
  }
  EXPECT_EQ(inside, 1);
  EXPECT_EQ(omp_get_max_active_levels(), levels);
  EXPECT_EQ(after, levels > 0 ? 2 : 1);
}

}  // namespace
}  // namespace gipsi
