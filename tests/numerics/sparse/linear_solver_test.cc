// Properties every solver behind MakeLinearSolver must have, run for each of them on two
// matrices: a shifted 3-D Laplacian and a stiffness-shaped spring lattice.

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gipsi/numerics/sparse/linear_solver.h"
#include "numerics/sparse/sparse_test_util.h"

namespace gipsi {
namespace {

using testing::IndependentRelativeResidual;
using testing::Manufacture;

struct SolverCase {
  std::string type;
  std::string preconditioner;
};

LinearSolverOptions OptionsFor(const SolverCase& c) {
  LinearSolverOptions options;
  options.type = c.type;
  options.preconditioner = c.preconditioner;
  return options;
}

std::string CaseName(const ::testing::TestParamInfo<SolverCase>& info) {
  return info.param.type == "cg" ? "cg_" + info.param.preconditioner : info.param.type;
}

class SparseLinearSolver : public ::testing::TestWithParam<SolverCase> {
 protected:
  std::unique_ptr<LinearSolver> MakeSolver() const {
    return MakeLinearSolver(OptionsFor(GetParam()));
  }
};

TEST_P(SparseLinearSolver, SolvesManufacturedProblemsToTolerance) {
  const double tolerance = LinearSolverOptions{}.tolerance;
  for (const SparseMatrix& A : {testing::TestLaplacian(), testing::TestLattice()}) {
    const auto problem = Manufacture(A);
    auto solver = MakeSolver();
    solver->AnalyzePattern(A);
    ASSERT_TRUE(solver->Factorize(A));
    VecX x = VecX::Zero(A.rows());
    const LinearSolveStats stats = solver->Solve(problem.b, x);
    EXPECT_TRUE(stats.converged);
    EXPECT_LE(stats.relative_residual, tolerance);
    // The reported residual is the true one, not a recurrence: recompute it independently.
    const double residual = IndependentRelativeResidual(A, problem.b, x);
    EXPECT_LE(residual, tolerance);
    EXPECT_NEAR(stats.relative_residual, residual, 1e-3 * residual + 1e-15);
    if (GetParam().type != "cg") {
      EXPECT_EQ(stats.iterations, 0);
    }
  }
}

TEST_P(SparseLinearSolver, ZeroRightHandSideGivesZeroSolutionAndConverges) {
  const SparseMatrix A = testing::TestLaplacian();
  auto solver = MakeSolver();
  solver->AnalyzePattern(A);
  ASSERT_TRUE(solver->Factorize(A));
  VecX x = testing::RandomVector(A.rows(), 1);  // a non-zero guess must not survive
  const LinearSolveStats stats = solver->Solve(VecX::Zero(A.rows()), x);
  EXPECT_TRUE(stats.converged);
  EXPECT_EQ(stats.iterations, 0);
  EXPECT_EQ(stats.relative_residual, 0.0);
  EXPECT_EQ(x, VecX::Zero(A.rows()));
}

TEST_P(SparseLinearSolver, NonFiniteRightHandSideStopsWithoutConverging) {
  const SparseMatrix A = testing::TestLaplacian();
  auto solver = MakeSolver();
  solver->AnalyzePattern(A);
  ASSERT_TRUE(solver->Factorize(A));
  for (double bad :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    VecX b = Manufacture(A).b;
    b[17] = bad;
    VecX x = VecX::Zero(A.rows());
    const LinearSolveStats stats = solver->Solve(b, x);
    EXPECT_FALSE(stats.converged);
    EXPECT_FALSE(stats.relative_residual <= LinearSolverOptions{}.tolerance);
  }
}

TEST_P(SparseLinearSolver, NonFiniteMatrixFailsFactorizeAndSolveReportsFailure) {
  SparseMatrix A = testing::TestLaplacian();
  auto solver = MakeSolver();
  solver->AnalyzePattern(A);
  A.valuePtr()[5] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(solver->Factorize(A));
  VecX x = VecX::Zero(A.rows());
  const LinearSolveStats stats = solver->Solve(VecX::Ones(A.rows()), x);
  EXPECT_FALSE(stats.converged);
  EXPECT_EQ(x, VecX::Zero(A.rows()));  // left alone
}

TEST_P(SparseLinearSolver, SolveBeforeAnyFactorizeReportsNotConverged) {
  auto solver = MakeSolver();
  VecX x;
  const LinearSolveStats stats = solver->Solve(VecX::Ones(4), x);
  EXPECT_FALSE(stats.converged);
  EXPECT_EQ(stats.relative_residual, std::numeric_limits<double>::infinity());
}

// Factorize without AnalyzePattern analyses first (documented convenience), and a solver can
// be moved to a new pattern by analysing again.
TEST_P(SparseLinearSolver, ReanalysingMovesTheSolverToANewPattern) {
  auto solver = MakeSolver();
  const SparseMatrix small = MakeLaplacian3D(6, 0.1);
  ASSERT_TRUE(solver->Factorize(small));
  VecX x;
  EXPECT_TRUE(solver->Solve(Manufacture(small).b, x).converged);

  const SparseMatrix lattice = testing::TestLattice();
  solver->AnalyzePattern(lattice);
  ASSERT_TRUE(solver->Factorize(lattice));
  const auto problem = Manufacture(lattice);
  x.setZero(lattice.rows());
  EXPECT_TRUE(solver->Solve(problem.b, x).converged);
  EXPECT_LE(IndependentRelativeResidual(lattice, problem.b, x), LinearSolverOptions{}.tolerance);
}

INSTANTIATE_TEST_SUITE_P(AllSolvers, SparseLinearSolver,
                         ::testing::Values(SolverCase{"cg", "none"}, SolverCase{"cg", "jacobi"},
                                           SolverCase{"cg", "sgs"}, SolverCase{"cg", "ic"},
                                           SolverCase{"cg", "cholesky"}, SolverCase{"cg", "amg"},
                                           SolverCase{"ldlt", "ic"}, SolverCase{"cholmod", "ic"}),
                         CaseName);

TEST(SparseLinearSolver, NamesSayWhichSolverAndPreconditioner) {
  EXPECT_EQ(MakeLinearSolver(OptionsFor({"cg", "ic"}))->name(), "cg+ic");
  EXPECT_EQ(MakeLinearSolver(OptionsFor({"cg", "cholesky"}))->name(), "cg+cholesky");
  EXPECT_EQ(MakeLinearSolver(OptionsFor({"cg", "amg"}))->name(), "cg+amg");
  EXPECT_EQ(MakeLinearSolver(OptionsFor({"ldlt", "ic"}))->name(), "ldlt");
  EXPECT_EQ(MakeLinearSolver(OptionsFor({"cholmod", "none"}))->name(), "cholmod");
}

}  // namespace
}  // namespace gipsi
