// Direct solvers (Eigen SimplicialLDLT, CHOLMOD supernodal LLᵀ, UMFPACK LU): SPD checks, indefinite
// matrices once accepted, recovery after a failed factorisation, reuse of the symbolic analysis,
// and their stats.

#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <omp.h>

#include "gipsi/numerics/simd.h"
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

namespace gipsi {
namespace {

/// The symmetric saddle-point matrix [[A, Bᵀ], [B, 0]] of a discrete Stokes-like problem: A the
/// shifted 3D Laplacian on n³ nodes, B one constraint row per group of `stride` consecutive
/// nodes (their sum), so B has full row rank and the matrix is nonsingular but indefinite,
/// with a zero diagonal block.
SparseMatrix SaddlePoint(int n, int stride) {
  const SparseMatrix a = MakeLaplacian3D(n, 0.1);
  const Index nu = a.rows();
  const Index np = nu / stride;
  std::vector<Eigen::Triplet<double, int>> t;
  for (int k = 0; k < a.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(a, k); it; ++it)
      t.emplace_back(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
  for (Index c = 0; c < np; ++c) {
    for (Index j = 0; j < stride; ++j) {
      const int row = static_cast<int>(nu + c), col = static_cast<int>(c * stride + j);
      t.emplace_back(row, col, 1.0);
      t.emplace_back(col, row, 1.0);
    }
  }
  SparseMatrix m(nu + np, nu + np);
  m.setFromTriplets(t.begin(), t.end());
  m.makeCompressed();
  return m;
}

// The fully incompressible mixed elements give exactly such matrices: UMFPACK's pivoting
// factorises them (with or without AcceptIndefinite, which it always grants) and solves to
// round-off (condition number of order 1e3 here, so 1e-10 is a loose bound on a round-off
// residual near 1e-15).
// CHOLMOD's factor is solved by SupernodalSolve: the two halves of the nested dissection on two
// threads, the separators after them. The 5,184-row lattice is above its two-thread size. The
// solution must be that of a backward-stable triangular solve, and the same bits on one thread
// or two and with either kernel set (the groups and the buffer of separator updates are the
// same whatever runs them).
void ExpectAccurateAndTheSameBitsOnAnyTeamAndKernelSet(const SparseMatrix& A) {
  const auto problem = Manufacture(A);
  auto solve = [&](int threads, SimdKernels kernels) {
    const testing::ScopedTeamAndKernels team(threads, kernels);
    LinearSolverOptions options;
    options.type = "cholmod";
    auto solver = MakeLinearSolver(options);
    solver->AnalyzePattern(A);
    EXPECT_TRUE(solver->Factorize(A));
    VecX x = VecX::Zero(A.rows());
    const LinearSolveStats stats = solver->Solve(problem.b, x);
    EXPECT_TRUE(stats.converged);
    return x;
  };
  const VecX reference = solve(1, SimdKernels::kGeneric);
  // Measured: relative residual 3.7e-16 and error 1.1e-13. A backward-stable solve leaves a few
  // ε of residual (1e-13 allows for the order of the sums, not for a wrong update), and an error
  // of at most the condition number times that (1e-9 allows a condition number of 1e6).
  EXPECT_LT(IndependentRelativeResidual(A, problem.b, reference), 1e-13);
  EXPECT_LT((reference - problem.x_true).norm() / problem.x_true.norm(), 1e-9);
  for (int threads : {1, 2}) {
    for (SimdKernels kernels : {SimdKernels::kAvx, SimdKernels::kGeneric}) {
      const VecX x = solve(threads, kernels);
      EXPECT_TRUE(testing::SameBits(x, reference))
          << threads << " threads, " << SimdKernelsName(kernels) << " kernels";
    }
  }
}

TEST(Cholmod, TheTwoThreadSolveIsAccurateAndTheSameBitsOnAnyTeamAndKernelSet) {
  ExpectAccurateAndTheSameBitsOnAnyTeamAndKernelSet(testing::TestLattice());
}

// Two independent blocks (two bodies in one system): the elimination tree is a forest, and
// the threads take its trees.
TEST(Cholmod, TheTwoThreadSolveTakesTheTreesOfABlockDiagonalMatrix) {
  const SparseMatrix block = testing::TestLattice();
  const Index n = block.rows();
  std::vector<Eigen::Triplet<double>> entries;
  for (Index offset : {Index{0}, n})
    for (int k = 0; k < block.outerSize(); ++k)
      for (SparseMatrix::InnerIterator it(block, k); it; ++it)
        entries.emplace_back(static_cast<int>(it.row() + offset),
                             static_cast<int>(it.col() + offset), it.value());
  SparseMatrix A(2 * n, 2 * n);
  A.setFromTriplets(entries.begin(), entries.end());
  A.makeCompressed();
  ExpectAccurateAndTheSameBitsOnAnyTeamAndKernelSet(A);
}

TEST(Umfpack, SolvesASymmetricSaddlePointWithAZeroBlock) {
  const SparseMatrix m = SaddlePoint(8, 4);
  LinearSolverOptions options;
  options.type = "umfpack";
  auto solver = MakeLinearSolver(options);
  EXPECT_EQ(solver->name(), "umfpack");
  EXPECT_TRUE(solver->AcceptIndefinite());
  solver->AnalyzePattern(m);
  ASSERT_TRUE(solver->Factorize(m));
  const auto problem = Manufacture(m, 3);
  VecX x;
  const LinearSolveStats stats = solver->Solve(problem.b, x);
  EXPECT_TRUE(stats.converged);
  EXPECT_LE(IndependentRelativeResidual(m, problem.b, x), 1e-10);
  EXPECT_LE((x - problem.x_true).norm(), 1e-8 * problem.x_true.norm());
}

// A nonsymmetric matrix of symmetric pattern (the exact tangent of a follower load): the
// Laplacian plus a skew part as large as its off-diagonal. Its residual check must use A x,
// not the symmetric product (which computes Aᵀ x): a solution to round-off, 1e-10 as above.
TEST(Umfpack, SolvesANonsymmetricMatrixOfSymmetricPattern) {
  SparseMatrix m = MakeLaplacian3D(8, 0.1);
  for (int k = 0; k < m.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(m, k); it; ++it)
      if (it.row() > it.col())
        it.valueRef() += 0.5;
      else if (it.row() < it.col())
        it.valueRef() -= 0.5;
  LinearSolverOptions options;
  options.type = "umfpack";
  auto solver = MakeLinearSolver(options);
  solver->AnalyzePattern(m);
  ASSERT_TRUE(solver->Factorize(m));
  const VecX x_true = testing::RandomVector(m.rows(), 9);
  const VecX b = m * x_true;
  VecX x;
  const LinearSolveStats stats = solver->Solve(b, x);
  EXPECT_TRUE(stats.converged);
  EXPECT_LE((b - m * x).norm(), 1e-10 * b.norm());
  EXPECT_LE((x - x_true).norm(), 1e-8 * x_true.norm());
}

// A constraint row repeated makes the saddle point singular: Factorize says so.
TEST(Umfpack, ASingularMatrixFailsFactorize) {
  SparseMatrix m = SaddlePoint(4, 4);
  const Index nu = 64;
  // Make constraint 1 a copy of constraint 0 (same columns 0..3): rows nu and nu + 1 equal.
  std::vector<Eigen::Triplet<double, int>> t;
  for (int k = 0; k < m.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(m, k); it; ++it) {
      const bool touches_second = it.row() == nu + 1 || it.col() == nu + 1;
      if (!touches_second)
        t.emplace_back(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
    }
  for (int j = 0; j < 4; ++j) {
    t.emplace_back(static_cast<int>(nu + 1), j, 1.0);
    t.emplace_back(j, static_cast<int>(nu + 1), 1.0);
  }
  SparseMatrix singular(m.rows(), m.cols());
  singular.setFromTriplets(t.begin(), t.end());
  singular.makeCompressed();
  LinearSolverOptions options;
  options.type = "umfpack";
  auto solver = MakeLinearSolver(options);
  solver->AnalyzePattern(singular);
  EXPECT_FALSE(solver->Factorize(singular));
  VecX x;
  EXPECT_FALSE(solver->Solve(VecX::Ones(m.rows()), x).converged);
}

}  // namespace
}  // namespace gipsi
