// Conjugate-gradient specifics: iteration counts per preconditioner, warm starts, the iteration
// budget, determinism, and the lagged Cholesky preconditioner's refactorisation policy.

#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <omp.h>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/OrderingMethods>

#include "gipsi/numerics/sparse/linear_solver.h"
#include "gipsi/numerics/sparse/model_problems.h"
#include "gipsi/numerics/sparse/vector_ops.h"
#include "numerics/sparse/sparse_test_util.h"

namespace gipsi {
namespace {

using testing::IndependentRelativeResidual;
using testing::Manufacture;

LinearSolverOptions Cg(const std::string& preconditioner) {
  LinearSolverOptions options;
  options.type = "cg";
  options.preconditioner = preconditioner;
  return options;
}

/// A solver analysed and factorised for A (asserting success).
std::unique_ptr<LinearSolver> ReadySolver(const LinearSolverOptions& options,
                                          const SparseMatrix& A) {
  auto solver = MakeLinearSolver(options);
  solver->AnalyzePattern(A);
  EXPECT_TRUE(solver->Factorize(A));
  return solver;
}

/// CG iterations from x = 0 on the test lattice (a stiff inclusion makes Jacobi useful).
TEST(Pcg, StrongerPreconditionersNeedFarFewerIterations) {
  const SparseMatrix A = testing::TestLattice();
  const auto problem = Manufacture(A);
  std::map<std::string, int> iterations;
  for (const char* preconditioner : {"none", "jacobi", "ic", "cholesky"}) {
    auto solver = ReadySolver(Cg(preconditioner), A);
    VecX x = VecX::Zero(A.rows());
    const LinearSolveStats stats = solver->Solve(problem.b, x);
    ASSERT_TRUE(stats.converged) << preconditioner;
    iterations[preconditioner] = stats.iterations;
  }
  // Measured: none 279, jacobi 175, ic 49, cholesky 1 (exact factor of this very matrix).
  EXPECT_LT(iterations["jacobi"], iterations["none"]);
  EXPECT_LT(3 * iterations["ic"], iterations["jacobi"]);
  EXPECT_LE(iterations["cholesky"], 2);
}

TEST(Pcg, WarmStartFromSolutionTakesNoIterations) {
  const SparseMatrix A = testing::TestLattice();
  const auto problem = Manufacture(A);
  for (const char* preconditioner : {"none", "jacobi", "ic", "cholesky"}) {
    auto solver = ReadySolver(Cg(preconditioner), A);
    VecX x = problem.x_true;
    const LinearSolveStats stats = solver->Solve(problem.b, x);
    EXPECT_TRUE(stats.converged) << preconditioner;
    EXPECT_EQ(stats.iterations, 0) << preconditioner;
    EXPECT_EQ(x, problem.x_true) << preconditioner;
  }
}

TEST(Pcg, WarmStartNearTheSolutionTakesFewerIterationsThanZero) {
  const SparseMatrix A = testing::TestLattice();
  const auto problem = Manufacture(A);
  auto solver = ReadySolver(Cg("jacobi"), A);
  VecX cold = VecX::Zero(A.rows());
  const int cold_iterations = solver->Solve(problem.b, cold).iterations;
  VecX warm = problem.x_true + 1e-3 * testing::RandomVector(A.rows(), 99);
  const LinearSolveStats stats = solver->Solve(problem.b, warm);
  EXPECT_TRUE(stats.converged);
  EXPECT_LT(stats.iterations, cold_iterations);
  EXPECT_LE(IndependentRelativeResidual(A, problem.b, warm), LinearSolverOptions{}.tolerance);
}

TEST(Pcg, InitialGuessOfWrongSizeIsTreatedAsZero) {
  const SparseMatrix A = testing::TestLaplacian();
  const auto problem = Manufacture(A);
  auto solver = ReadySolver(Cg("ic"), A);
  VecX empty;
  VecX zero = VecX::Zero(A.rows());
  const LinearSolveStats from_empty = solver->Solve(problem.b, empty);
  const LinearSolveStats from_zero = solver->Solve(problem.b, zero);
  EXPECT_TRUE(from_empty.converged);
  EXPECT_EQ(from_empty.iterations, from_zero.iterations);
  EXPECT_EQ(empty, zero);
}

TEST(Pcg, StopsAtIterationBudgetAndReportsTrueResidual) {
  const SparseMatrix A = testing::TestLattice();
  const auto problem = Manufacture(A);
  LinearSolverOptions options = Cg("none");
  options.max_iterations = 5;
  auto solver = ReadySolver(options, A);
  VecX x = VecX::Zero(A.rows());
  const LinearSolveStats stats = solver->Solve(problem.b, x);
  EXPECT_FALSE(stats.converged);
  EXPECT_EQ(stats.iterations, 5);
  const double residual = IndependentRelativeResidual(A, problem.b, x);
  EXPECT_GT(residual, options.tolerance);
  EXPECT_NEAR(stats.relative_residual, residual, 1e-9 * residual);
}

TEST(Pcg, NonFiniteInitialGuessStopsWithoutIterating) {
  const SparseMatrix A = testing::TestLaplacian();
  auto solver = ReadySolver(Cg("jacobi"), A);
  VecX x = VecX::Zero(A.rows());
  x[3] = std::numeric_limits<double>::infinity();
  const LinearSolveStats stats = solver->Solve(Manufacture(A).b, x);
  EXPECT_FALSE(stats.converged);
  EXPECT_EQ(stats.iterations, 0);
  EXPECT_FALSE(std::isfinite(stats.relative_residual));
}

// The "ic" preconditioner hands Eigen's IncompleteCholesky<Lower> the full symmetric matrix
// (PCG needs both triangles for its SpMV). It must read only the lower triangle: the result
// equals that of the lower triangle alone, bit for bit.
TEST(Pcg, IncompleteCholeskyOfFullMatrixEqualsThatOfItsLowerTriangle) {
  const SparseMatrix A = testing::TestLattice();
  const SparseMatrix lower = A.triangularView<Eigen::Lower>();
  Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>> from_full, from_lower;
  from_full.compute(A);
  from_lower.compute(lower);
  ASSERT_EQ(from_full.info(), Eigen::Success);
  ASSERT_EQ(from_lower.info(), Eigen::Success);
  const VecX r = testing::RandomVector(A.rows(), 8);
  const VecX z_full = from_full.solve(r);
  const VecX z_lower = from_lower.solve(r);
  EXPECT_EQ(std::memcmp(z_full.data(), z_lower.data(), sizeof(double) * z_full.size()), 0);
}

// A matrix with a negative diagonal entry is not SPD: Jacobi refuses it at Factorize time.
TEST(Pcg, JacobiRejectsNonPositiveDiagonal) {
  SparseMatrix A = testing::TestLaplacian();
  A.coeffRef(10, 10) = -1.0;
  auto solver = MakeLinearSolver(Cg("jacobi"));
  solver->AnalyzePattern(A);
  EXPECT_FALSE(solver->Factorize(A));
}

// On an indefinite matrix CG may meet p·Ap ≤ 0; whatever happens it must stop and report
// honestly (here: the budget is small, so it cannot run long either way).
TEST(Pcg, IndefiniteMatrixTerminatesAndReportsHonestly) {
  const SparseMatrix A = MakeLaplacian3D(10, -1.0);
  const auto problem = Manufacture(A);
  LinearSolverOptions options = Cg("none");
  options.max_iterations = 500;
  auto solver = ReadySolver(options, A);
  VecX x = VecX::Zero(A.rows());
  const LinearSolveStats stats = solver->Solve(problem.b, x);
  EXPECT_LE(stats.iterations, options.max_iterations);
  const double residual = IndependentRelativeResidual(A, problem.b, x);
  EXPECT_EQ(stats.converged, residual <= options.tolerance);
}

// Large enough (9,261 rows) for the parallel reductions; the same thread count gives the same
// bits on every run. A budget of 10 iterations keeps the test short on a loaded machine, where
// every parallel region may wait for a descheduled thread; the iterates are compared anyway.
TEST(Pcg, RepeatedSolvesGiveIdenticalBits) {
  const SparseMatrix A = MakeLaplacian3D(21, 1e-2);
  ASSERT_GE(A.rows(), kMinParallelLength);
  const auto problem = Manufacture(A);
  for (const char* preconditioner : {"jacobi", "ic", "amg"}) {
    LinearSolverOptions options = Cg(preconditioner);
    options.max_iterations = 10;
    auto solver = ReadySolver(options, A);
    VecX first = VecX::Zero(A.rows());
    const LinearSolveStats stats = solver->Solve(problem.b, first);
    VecX again = VecX::Zero(A.rows());
    const LinearSolveStats stats_again = solver->Solve(problem.b, again);
    EXPECT_EQ(stats_again.iterations, stats.iterations);
    EXPECT_EQ(std::memcmp(&stats_again.relative_residual, &stats.relative_residual, sizeof(double)),
              0);
    EXPECT_EQ(std::memcmp(first.data(), again.data(), sizeof(double) * first.size()), 0)
        << preconditioner;
  }
}

// Jacobi and unpreconditioned CG run the fused Chronopoulos–Gear iteration in one parallel
// region (pcg.cc). In exact arithmetic its iterates are textbook PCG's, so Eigen's own
// ConjugateGradient with the diagonal preconditioner, run to the same relative residual, is an
// independent reference for the iteration count. Both are checked on a node-block matrix (the
// spring lattice, NodeBlockSpMV) and on a scalar one (the Laplacian), with 1, 2 and 3 threads
// (3 splits the rows unevenly, and the lattice's into whole nodes). The rows are summed in fixed
// blocks whatever the team, so every thread count gives the same bits: a solve may then choose
// its team from call to call (AdaptiveParallel) without changing a result.
TEST(Pcg, FusedIterationMatchesTextbookPcgForAnyThreadCount) {
  struct Case {
    const char* name;
    SparseMatrix A;
  };
  const Case cases[] = {
      {"lattice",
       MakeSpringLattice3D(15, 1e-2, [](const Vec3& p) { return p.z() > 0.5 ? 20.0 : 1.0; })},
      {"laplacian", MakeLaplacian3D(22, 1e-2)}};
  const int saved = omp_get_max_threads();
  for (const Case& c : cases) {
    ASSERT_GE(c.A.rows(), kMinParallelLength) << c.name;  // the parallel path
    const auto problem = Manufacture(c.A);
    Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower | Eigen::Upper> reference;
    reference.setTolerance(1e-8);
    reference.setMaxIterations(5000);
    reference.compute(c.A);
    const VecX expected = reference.solve(problem.b);
    ASSERT_EQ(reference.info(), Eigen::Success) << c.name;
    for (const char* preconditioner : {"jacobi", "none"}) {
      VecX one_thread;
      int one_thread_iterations = -1;
      for (int threads : {1, 2, 3}) {
        omp_set_num_threads(threads);
        LinearSolverOptions options = Cg(preconditioner);
        options.tolerance = 1e-8;
        options.max_iterations = 5000;
        auto solver = ReadySolver(options, c.A);
        VecX x = VecX::Zero(c.A.rows());
        const LinearSolveStats stats = solver->Solve(problem.b, x);
        omp_set_num_threads(saved);
        const std::string what =
            std::string(c.name) + " " + preconditioner + " " + std::to_string(threads) + " threads";
        ASSERT_TRUE(stats.converged) << what;
        EXPECT_LE(IndependentRelativeResidual(c.A, problem.b, x), 1e-8) << what;
        if (std::string(preconditioner) == "jacobi") {
          // Rounding makes long CG runs differ by a few iterations between any two correct
          // implementations (here ~200-400 iterations); 5 % covers that and no more: a lost
          // conjugacy or a wrong step length costs far more.
          EXPECT_NEAR(stats.iterations, static_cast<double>(reference.iterations()),
                      0.05 * static_cast<double>(reference.iterations()))
              << what;
        }
        // Both solutions agree to what the residual bounds (‖x − x*‖ ≤ κ ‖r‖ / ‖A‖, and κ of
        // these matrices is below 1e4 by their spectra): 1e-4 relative.
        EXPECT_LE((x - expected).norm(), 1e-4 * expected.norm()) << what;
        if (threads == 1) {
          one_thread = x;
          one_thread_iterations = stats.iterations;
        } else {
          EXPECT_EQ(stats.iterations, one_thread_iterations) << what;
          EXPECT_EQ(0, std::memcmp(x.data(), one_thread.data(),
                                   sizeof(double) * static_cast<std::size_t>(x.size())))
              << what << ": not the bits of one thread";
        }
      }
    }
  }
}

// The fused CG keeps a block-row copy of a node-block matrix (pcg.cc): it must follow the
// matrix through a failed Factorize, a successful one, and a new pattern without node blocks.
TEST(Pcg, JacobiFollowsFailedFactorizeAndNewPattern) {
  const SparseMatrix A = testing::TestLattice();
  ASSERT_TRUE(HasNodeBlockPattern(A));
  const auto problem = Manufacture(A);
  auto solver = ReadySolver(Cg("jacobi"), A);
  VecX x = VecX::Zero(A.rows());
  ASSERT_TRUE(solver->Solve(problem.b, x).converged);

  SparseMatrix broken = A;
  broken.valuePtr()[7] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(solver->Factorize(broken));
  x.setZero();
  EXPECT_FALSE(solver->Solve(problem.b, x).converged);

  const SparseMatrix stiffer = testing::TestLattice(3.0);  // same pattern, new values
  const auto stiff_problem = Manufacture(stiffer);
  ASSERT_TRUE(solver->Factorize(stiffer));
  x.setZero();
  ASSERT_TRUE(solver->Solve(stiff_problem.b, x).converged);
  EXPECT_LE(IndependentRelativeResidual(stiffer, stiff_problem.b, x), 1e-6);

  EXPECT_LE(testing::SolveScalarLaplacian(*solver), 1e-6);  // no node blocks: Jacobi
}

TEST(LaggedCholeskyPcg, FirstFactorizeFactorizesAndConvergesInOneIteration) {
  const SparseMatrix A = testing::TestLattice();
  auto solver = ReadySolver(Cg("cholesky"), A);
  VecX x = VecX::Zero(A.rows());
  const LinearSolveStats stats = solver->Solve(Manufacture(A).b, x);
  EXPECT_TRUE(stats.refactorized);
  EXPECT_TRUE(stats.converged);
  EXPECT_EQ(stats.iterations, 1);
}

// Springs 5 % stiffer everywhere (A1 − A0 = 0.05·K0, between 0 and 0.05·A0): the old factor
// keeps CG within a few iterations and Factorize does not refactorise. (Scaling only the
// off-diagonal entries by 1.05 would make these weakly shifted matrices indefinite.)
TEST(LaggedCholeskyPcg, SlightlyChangedMatrixConvergesFastWithoutRefactorizing) {
  const SparseMatrix A0 = testing::TestLattice();
  const SparseMatrix A1 = testing::TestLattice(1.05);
  auto solver = ReadySolver(Cg("cholesky"), A0);
  ASSERT_TRUE(solver->Factorize(A1));
  const auto problem = Manufacture(A1);
  VecX x = VecX::Zero(A1.rows());
  const LinearSolveStats stats = solver->Solve(problem.b, x);
  EXPECT_FALSE(stats.refactorized);
  EXPECT_TRUE(stats.converged);
  EXPECT_LE(stats.iterations, 5);  // measured: 2
  EXPECT_LE(IndependentRelativeResidual(A1, problem.b, x), LinearSolverOptions{}.tolerance);

  // Solving with the old factor was cheap, so the next Factorize does not refactorise either.
  ASSERT_TRUE(solver->Factorize(A1));
  x.setZero();
  EXPECT_FALSE(solver->Solve(problem.b, x).refactorized);
}

// Move the stiff inclusion from the top half to the right half: the old factor is a poor
// preconditioner (more than refactor_iterations CG iterations), so the next Factorize
// refactorises and CG is back to one iteration.
TEST(LaggedCholeskyPcg, StronglyChangedMatrixTriggersRefactorizationOnNextFactorize) {
  const SparseMatrix A0 = testing::TestLattice();
  const SparseMatrix A1 =
      MakeSpringLattice3D(12, 1e-2, [](const Vec3& p) { return p.x() > 0.5 ? 20.0 : 1.0; });
  const LinearSolverOptions options = Cg("cholesky");
  auto solver = ReadySolver(options, A0);
  ASSERT_TRUE(solver->Factorize(A1));
  const auto problem = Manufacture(A1);
  VecX x = VecX::Zero(A1.rows());
  const LinearSolveStats lagged = solver->Solve(problem.b, x);
  EXPECT_FALSE(lagged.refactorized);
  EXPECT_GT(lagged.iterations, options.refactor_iterations);  // measured: 109

  ASSERT_TRUE(solver->Factorize(A1));
  x.setZero();
  const LinearSolveStats refreshed = solver->Solve(problem.b, x);
  EXPECT_TRUE(refreshed.refactorized);
  EXPECT_TRUE(refreshed.converged);
  EXPECT_EQ(refreshed.iterations, 1);
}

// A matrix that drifts further from the factorised one every step (springs stiffer along x by
// a factor 1 + 0.2 step x): CG iterations with the old factor rise slowly, far below
// refactor_iterations, yet the amortised rule refactorises once a solve costs more than the mean
// per solve since the last factorisation (the factorisation's cost included), and CG is then back
// to ~1 iteration.
TEST(LaggedCholeskyPcg, SlowlyRisingIterationsTriggerAnAmortisedRefactorization) {
  LinearSolverOptions options = Cg("cholesky");
  options.refactor_iterations = 1000;  // only the amortised rule can refactorise
  const SparseMatrix A0 = testing::TestLattice();
  auto solver = ReadySolver(options, A0);
  std::vector<int> iterations;
  int refactorized_at = -1;
  std::vector<SparseMatrix> matrices;
  for (int step = 1; step <= 40 && refactorized_at < 0; ++step) {
    matrices.push_back(MakeSpringLattice3D(12, 1e-2, [step](const Vec3& p) {
      return (p.z() > 0.5 ? 20.0 : 1.0) * (1.0 + 0.2 * step * p.x());
    }));
    const SparseMatrix& A = matrices.back();
    ASSERT_TRUE(solver->Factorize(A));
    const auto problem = Manufacture(A);
    VecX x = VecX::Zero(A.rows());
    const LinearSolveStats stats = solver->Solve(problem.b, x);
    ASSERT_TRUE(stats.converged);
    if (stats.refactorized) {
      refactorized_at = step;
      EXPECT_LE(stats.iterations, 2);  // the factor of this very matrix
    }
    iterations.push_back(stats.iterations);
  }
  ASSERT_GT(refactorized_at, 1) << "never refactorised";
  // Before the refactorisation the iterations rose but stayed far below the cap (measured: 5
  // rising to 13, refactorised at step 16).
  EXPECT_GT(iterations[static_cast<std::size_t>(refactorized_at) - 2], iterations.front());
  EXPECT_LT(iterations[static_cast<std::size_t>(refactorized_at) - 2], 100);
}

TEST(LaggedCholeskyPcg, UnconvergedSolveAlsoTriggersRefactorization) {
  const SparseMatrix A0 = testing::TestLattice();
  const SparseMatrix A1 = testing::TestLattice(1.05);
  LinearSolverOptions options = Cg("cholesky");
  options.tolerance = 1e-14;
  options.max_iterations = 1;  // one iteration with the old factor cannot reach 1e-14
  auto solver = ReadySolver(options, A0);
  ASSERT_TRUE(solver->Factorize(A1));
  VecX x = VecX::Zero(A1.rows());
  ASSERT_FALSE(solver->Solve(Manufacture(A1).b, x).converged);
  ASSERT_TRUE(solver->Factorize(A1));
  EXPECT_TRUE(solver->Solve(Manufacture(A1).b, x).refactorized);
}

TEST(LaggedCholeskyPcg, IndefiniteMatrixFailsFactorize) {
  const SparseMatrix A = MakeLaplacian3D(8, -1.0);
  auto solver = MakeLinearSolver(Cg("cholesky"));
  solver->AnalyzePattern(A);
  EXPECT_FALSE(solver->Factorize(A));
  // And recovers on an SPD matrix of the same pattern.
  const SparseMatrix B = MakeLaplacian3D(8, 0.1);
  ASSERT_TRUE(solver->Factorize(B));
  VecX x = VecX::Zero(B.rows());
  const LinearSolveStats stats = solver->Solve(Manufacture(B).b, x);
  EXPECT_TRUE(stats.refactorized);
  EXPECT_TRUE(stats.converged);
}

}  // namespace
}  // namespace gipsi
