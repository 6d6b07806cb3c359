#include <algorithm>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>
#include <omp.h>

#include "gipsi/numerics/simd.h"
#include "gipsi/numerics/sparse/linear_solver.h"
#include "gipsi/numerics/sparse/model_problems.h"
#include "gipsi/numerics/sparse/node_block_copy.h"
#include "gipsi/numerics/sparse/vector_ops.h"
#include "numerics/sparse/sparse_test_util.h"

namespace gipsi {
namespace {

using testing::RandomVector;
using testing::SameBits;

/// Restores the OpenMP thread count when a test changed it.
class ThreadCountGuard {
 public:
  ThreadCountGuard() : saved_(omp_get_max_threads()) {}
  ~ThreadCountGuard() { omp_set_num_threads(saved_); }
  ThreadCountGuard(const ThreadCountGuard&) = delete;
  ThreadCountGuard& operator=(const ThreadCountGuard&) = delete;

 private:
  int saved_;
};

// Both model matrices are large enough (≥ kMinParallelLength rows) to take the parallel path.
std::vector<SparseMatrix> ParallelSizedMatrices() {
  std::vector<SparseMatrix> matrices;
  matrices.push_back(MakeLaplacian3D(21, 0.5));  // 9,261 rows
  matrices.push_back(MakeSpringLattice3D(14, 1e-2, [](const Vec3& p) { return 1.0 + p.x(); }));
  for (const SparseMatrix& A : matrices) EXPECT_GE(A.rows(), kMinParallelLength);
  return matrices;
}

TEST(SparseModelProblems, AreSymmetricWithTheDocumentedNonzeroCounts) {
  const SparseMatrix laplacian = MakeLaplacian3D(5, 0.1);
  EXPECT_EQ(laplacian.rows(), 125);
  EXPECT_EQ(laplacian.nonZeros(), 7 * 125 - 6 * 25);
  EXPECT_EQ((SparseMatrix(laplacian.transpose()) - laplacian).norm(), 0.0);
  EXPECT_DOUBLE_EQ(laplacian.coeff(62, 62), 6.1);

  const SparseMatrix lattice = MakeSpringLattice3D(4, 0.1);
  EXPECT_EQ(lattice.rows(), 3 * 64);
  EXPECT_EQ(lattice.nonZeros(), 9 * 10 * 10 * 10);
  EXPECT_EQ((SparseMatrix(lattice.transpose()) - lattice).norm(), 0.0);
}

// The lattice without its shift is a stiffness matrix: rigid translations and rotations are in
// its null space, so A·u = shift·u for them. This pins down the block assembly.
TEST(SparseModelProblems, LatticeMapsRigidMotionsToShiftTimesMotion) {
  const int n = 5;
  const double shift = 0.25;
  const SparseMatrix A = MakeSpringLattice3D(n, shift, [](const Vec3& p) { return 1.0 + p.y(); });
  const Vec3 translation(0.3, -1.0, 2.0);
  const Vec3 omega(0.5, 1.5, -0.7);
  VecX u(A.rows());
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const Vec3 p = Vec3(x, y, z) / (n - 1);
        u.segment<3>(3 * (x + n * (y + n * z))) = translation + omega.cross(p);
      }
  VecX Au(A.rows());
  SymmetricSpMV(A, u, Au);
  EXPECT_LT((Au - shift * u).norm(), 1e-12 * u.norm());
}

TEST(SymmetricSpMV, MatchesEigenProductToRoundOff) {
  for (const SparseMatrix& A : ParallelSizedMatrices()) {
    const VecX x = RandomVector(A.cols(), 3);
    VecX y(A.rows());
    SymmetricSpMV(A, x, y);
    const VecX expected = A * x;
    EXPECT_LE((y - expected).norm(), 1e-14 * expected.norm());
  }
}

TEST(SymmetricSpMV, RepeatedRunsGiveIdenticalBits) {
  for (const SparseMatrix& A : ParallelSizedMatrices()) {
    const VecX x = RandomVector(A.cols(), 4);
    VecX first(A.rows());
    VecX again(A.rows());
    SymmetricSpMV(A, x, first);
    for (int run = 0; run < 5; ++run) {
      again.setConstant(-1.0);
      SymmetricSpMV(A, x, again);
      EXPECT_TRUE(SameBits(first, again)) << "run " << run;
    }
  }
}

// Each y[j] is one sequential sum over column j, so even the thread count cannot change it.
TEST(SymmetricSpMV, BitsDoNotDependOnThreadCount) {
  ThreadCountGuard guard;
  for (const SparseMatrix& A : ParallelSizedMatrices()) {
    const VecX x = RandomVector(A.cols(), 5);
    omp_set_num_threads(1);
    VecX serial(A.rows());
    SymmetricSpMV(A, x, serial);
    for (int threads : {2, 3}) {
      omp_set_num_threads(threads);
      VecX parallel(A.rows());
      SymmetricSpMV(A, x, parallel);
      EXPECT_TRUE(SameBits(serial, parallel)) << threads << " threads";
      VecX alone(A.rows());  // the caller's choice of its own thread (AdaptiveParallel's)
      SymmetricSpMV(A, x, alone, /*team=*/false);
      EXPECT_TRUE(SameBits(serial, alone)) << threads << " threads, team off";
    }
  }
}

TEST(SymmetricSpMV, HandlesEmptyColumnsAndATinyMatrix) {
  SparseMatrix A(3, 3);  // diag(2, 0, 5) with the middle column empty
  A.insert(0, 0) = 2.0;
  A.insert(2, 2) = 5.0;
  A.makeCompressed();
  VecX x(3);
  x << 1.0, 7.0, -1.0;
  VecX y(3);
  SymmetricSpMV(A, x, y);
  EXPECT_EQ(y, VecX((VecX(3) << 2.0, 0.0, -5.0).finished()));
}

TEST(NodeBlockSpMV, RecognisesOnlyWholeNodeBlockPatterns) {
  EXPECT_TRUE(HasNodeBlockPattern(MakeSpringLattice3D(4, 0.1)));
  // 21³ = 9,261 rows, a multiple of 3, but a point (7-entry) pattern.
  EXPECT_FALSE(HasNodeBlockPattern(MakeLaplacian3D(21, 0.5)));
  // A lattice with one off-diagonal block entry (and its mirror) missing.
  SparseMatrix A = MakeSpringLattice3D(4, 0.1);
  SparseMatrix B(A.rows(), A.cols());
  std::vector<Eigen::Triplet<double>> entries;
  for (int j = 0; j < A.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(A, j); it; ++it)
      if (!((it.row() == 4 && j == 0) || (it.row() == 0 && j == 4)))
        entries.emplace_back(static_cast<int>(it.row()), j, it.value());
  B.setFromTriplets(entries.begin(), entries.end());
  B.makeCompressed();
  ASSERT_LT(B.nonZeros(), A.nonZeros());
  EXPECT_FALSE(HasNodeBlockPattern(B));
}

// Each y entry sums at most 27 blocks × 3 products in its own fixed order; the difference to
// Eigen's order is a few ulps of the entry's magnitude, far below 1e-14 of the norm.
TEST(NodeBlockSpMV, MatchesEigenProductToRoundOff) {
  const SparseMatrix A = MakeSpringLattice3D(14, 1e-2, [](const Vec3& p) { return 1.0 + p.x(); });
  ASSERT_GE(A.rows(), kMinParallelLength);  // the parallel path
  ASSERT_TRUE(HasNodeBlockPattern(A));
  const VecX x = RandomVector(A.cols(), 21);
  VecX y(A.rows());
  NodeBlockSpMV(A, x, y);
  const VecX expected = A * x;
  EXPECT_LE((y - expected).norm(), 1e-14 * expected.norm());
}

TEST(NodeBlockSpMV, BitsDoNotDependOnThreadCount) {
  ThreadCountGuard guard;
  const SparseMatrix A = MakeSpringLattice3D(14, 1e-2, [](const Vec3& p) { return 1.0 + p.z(); });
  const VecX x = RandomVector(A.cols(), 22);
  omp_set_num_threads(1);
  VecX serial(A.rows());
  NodeBlockSpMV(A, x, serial);
  for (int threads : {2, 3}) {
    omp_set_num_threads(threads);
    VecX parallel(A.rows());
    NodeBlockSpMV(A, x, parallel);
    EXPECT_TRUE(SameBits(serial, parallel)) << threads << " threads";
  }
}

// The block-row copy the fused CG multiplies with: the same product as Eigen's to round-off
// (a different summation order than NodeBlockSpMV's), after new values are copied into the
// same pattern too, and with the same bits for any thread count and any split of the nodes.
TEST(NodeBlockCopy, MatchesEigenProductAndFollowsNewValues) {
  ThreadCountGuard guard;
  SparseMatrix A = MakeSpringLattice3D(14, 1e-2, [](const Vec3& p) { return 1.0 + p.x(); });
  ASSERT_GE(A.rows(), kMinParallelLength);  // the parallel path
  NodeBlockCopy copy;
  copy.Assign(A);
  ASSERT_EQ(copy.nodes(), A.cols() / 3);
  const VecX x = RandomVector(A.cols(), 23);
  VecX y(A.rows());
  copy.Multiply(x, y);
  VecX expected = A * x;
  EXPECT_LE((y - expected).norm(), 1e-14 * expected.norm());

  const SparseMatrix B =
      MakeSpringLattice3D(14, 2e-2, [](const Vec3& p) { return 2.0 + p.y() * p.z(); });
  ASSERT_EQ(B.nonZeros(), A.nonZeros());
  copy.CopyValues(B);
  copy.Multiply(x, y);
  expected = B * x;
  EXPECT_LE((y - expected).norm(), 1e-14 * expected.norm());

  omp_set_num_threads(1);
  VecX serial(B.rows());
  copy.Multiply(x, serial);
  EXPECT_TRUE(SameBits(serial, y));
  VecX pieces(B.rows());
  const int nodes = copy.nodes();
  for (int begin = 0; begin < nodes; begin += 997)  // an uneven split
    copy.MultiplyNodes(x.data(), pieces.data(), begin, std::min(begin + 997, nodes));
  EXPECT_TRUE(SameBits(serial, pieces));
  // Copied on the calling thread alone (team false): the same blocks.
  NodeBlockCopy alone;
  alone.Assign(A);
  alone.CopyValues(B, /*team=*/false);
  VecX from_alone(B.rows());
  alone.Multiply(x, from_alone);
  EXPECT_TRUE(SameBits(serial, from_alone));
  for (int threads : {2, 3}) {
    omp_set_num_threads(threads);
    VecX parallel(B.rows());
    copy.Multiply(x, parallel);
    EXPECT_TRUE(SameBits(serial, parallel)) << threads << " threads";
  }
}

// The AVX kernel (chosen when the processor has AVX) and the generic one give the same bits:
// the machine changes the speed of a product, not its result. Also on a matrix whose values
// span many magnitudes and signs, where a fused multiply-add or another order would round
// differently.
TEST(NodeBlockCopy, AvxAndGenericKernelsGiveTheSameBits) {
  SparseMatrix A = MakeSpringLattice3D(9, 1e-2, [](const Vec3& p) { return 1.0 + p.x(); });
  const VecX noise = RandomVector(A.nonZeros(), 5);
  for (Index k = 0; k < A.nonZeros(); ++k)  // symmetric: scale by a function of (row, col) sums
    A.valuePtr()[k] *= 1.0 + 1e3 * std::abs(noise[k % 7]);
  SparseMatrix symmetric = SparseMatrix(A.transpose()) + A;
  NodeBlockCopy copy;
  copy.Assign(symmetric);
  const VecX x = RandomVector(symmetric.cols(), 29) * 1e5;
  VecX active(symmetric.rows()), generic(symmetric.rows());
  copy.MultiplyNodes(x.data(), active.data(), 0, copy.nodes());
  const SimdKernels before = LimitSimdKernels(SimdKernels::kGeneric);
  EXPECT_EQ(ActiveSimdKernels(), SimdKernels::kGeneric);  // (the limit is restored below)
  copy.MultiplyNodes(x.data(), generic.data(), 0, copy.nodes());
  LimitSimdKernels(before);
  EXPECT_TRUE(SameBits(active, generic)) << "kernels: " << SimdKernelsName(ActiveSimdKernels());
  const VecX expected = symmetric * x;
  EXPECT_LE((generic - expected).norm(), 1e-14 * expected.norm());
}

TEST(ParallelDot, MatchesSerialDotAndRepeatsBitForBit) {
  ThreadCountGuard guard;
  omp_set_num_threads(3);  // an uneven split of the range
  const VecX a = RandomVector(100'003, 11);
  const VecX b = RandomVector(100'003, 12);
  ReductionScratch scratch;
  const double first = ParallelDot(a, b, scratch);
  EXPECT_NEAR(first, a.dot(b), 1e-12 * a.norm() * b.norm());
  for (int run = 0; run < 5; ++run) {
    const double again = ParallelDot(a, b, scratch);
    EXPECT_EQ(std::memcmp(&first, &again, sizeof(double)), 0) << "run " << run;
  }
  // On the calling thread alone (team false) the same blocks are added in the same order.
  const double alone = ParallelDot(a, b, scratch, /*team=*/false);
  EXPECT_EQ(std::memcmp(&first, &alone, sizeof(double)), 0);
}

}  // namespace
}  // namespace gipsi
