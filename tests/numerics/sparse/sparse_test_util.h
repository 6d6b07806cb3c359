#pragma once
/// @file
/// Shared fixtures for the sparse solver tests: manufactured problems and an independent
/// residual check (Eigen's own product, not SymmetricSpMV).

#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

#include <omp.h>

#include "gipsi/numerics/simd.h"
#include "gipsi/numerics/sparse/linear_solver.h"
#include "gipsi/numerics/sparse/model_problems.h"

namespace gipsi::testing {

/// A vector of uniform(−1, 1) entries from a fixed seed.
inline VecX RandomVector(Index size, std::uint32_t seed) {
  std::mt19937 engine(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  VecX v(size);
  for (Index i = 0; i < size; ++i) v[i] = uniform(engine);
  return v;
}

/// True if a and b hold the same bits (not just equal values).
inline bool SameBits(const VecX& a, const VecX& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

/// Runs the scope with `threads` OpenMP threads and at most `kernels` (numerics/simd.h), and
/// restores both when it ends (also on a failed ASSERT).
class ScopedTeamAndKernels {
 public:
  ScopedTeamAndKernels(int threads, SimdKernels kernels)
      : threads_(omp_get_max_threads()), kernels_(LimitSimdKernels(kernels)) {
    omp_set_num_threads(threads);
  }
  ScopedTeamAndKernels(const ScopedTeamAndKernels&) = delete;
  ScopedTeamAndKernels& operator=(const ScopedTeamAndKernels&) = delete;
  ~ScopedTeamAndKernels() {
    LimitSimdKernels(kernels_);
    omp_set_num_threads(threads_);
  }

 private:
  int threads_;
  SimdKernels kernels_;
};

/// A x_true = b with a random x_true; b is computed with SymmetricSpMV, so x_true has a
/// residual of exactly 0 under the solvers' own product.
struct ManufacturedProblem {
  VecX x_true;
  VecX b;
};

/// See ManufacturedProblem.
inline ManufacturedProblem Manufacture(const SparseMatrix& A, std::uint32_t seed = 7) {
  ManufacturedProblem p{RandomVector(A.rows(), seed), VecX(A.rows())};
  SymmetricSpMV(A, p.x_true, p.b);
  return p;
}

/// ‖b − A x‖ / ‖b‖ with Eigen's sparse product.
inline double IndependentRelativeResidual(const SparseMatrix& A, const VecX& b, const VecX& x) {
  const VecX r = b - A * x;
  return r.norm() / b.norm();
}

/// The test's "elasticity-like" matrix: a 12³-node spring lattice (5,184 rows) whose springs
/// are 20× stiffer in the upper half (a stiff inclusion), plus a small mass shift.
inline SparseMatrix TestLattice(double stiffness_scale = 1.0) {
  return MakeSpringLattice3D(12, 1e-2, [stiffness_scale](const Vec3& p) {
    return stiffness_scale * (p.z() > 0.5 ? 20.0 : 1.0);
  });
}

/// The test's Laplacian: 16³ unknowns (4,096 rows) plus a small shift.
inline SparseMatrix TestLaplacian() { return MakeLaplacian3D(16, 1e-2); }

/// Moves `solver` to a 12³ Laplacian (no node blocks: the node-block preconditioners' scalar
/// fallback) and solves a manufactured problem; returns ‖b − A x‖ / ‖b‖ by Eigen's product, or
/// +∞ if Factorize or Solve failed.
inline double SolveScalarLaplacian(LinearSolver& solver) {
  const SparseMatrix L = MakeLaplacian3D(12, 1e-2);
  if (HasNodeBlockPattern(L)) return std::numeric_limits<double>::infinity();
  const ManufacturedProblem problem = Manufacture(L);
  solver.AnalyzePattern(L);
  VecX y = VecX::Zero(L.rows());
  if (!solver.Factorize(L) || !solver.Solve(problem.b, y).converged)
    return std::numeric_limits<double>::infinity();
  return IndependentRelativeResidual(L, problem.b, y);
}

}  // namespace gipsi::testing
