#pragma once
/// @file
/// An iterative solver for the saddle-point systems of mixed (displacement–pressure) elements,
///
///     A = [[K, Bᵀ], [B, −C]]   (n_u displacement unknowns first, then the pressures),
///
/// for meshes whose LU (UMFPACK) fills too much: restarted GMRES (Saad & Schultz, SIAM J. Sci.
/// Stat. Comput. 7, 1986) on A, right-preconditioned by the block-triangular
///
///     P = [[K̂, 0], [B, −Ŝ]],   P⁻¹ (v_u, v_p) = (K̂⁻¹ v_u,  Ŝ⁻¹ (B K̂⁻¹ v_u − v_p)),
///
/// with K̂ the symmetric part of the displacement block, factorised by CHOLMOD (supernodal LLᵀ,
/// LDLᵀ where it is indefinite), and Ŝ an approximation of the Schur complement C + B K⁻¹ Bᵀ
/// given by the caller: for incompressible elasticity the pressure mass matrix over the shear
/// modulus is spectrally equivalent to it, so the iteration count does not grow with the mesh
/// (Elman, Silvester & Wathen, "Finite elements and fast iterative solvers", 2nd ed., 2014,
/// ch. 4 and 9). With the exact blocks GMRES would finish in two iterations; the nonsymmetric
/// part of K (a follower load's tangent) and the approximations of Ŝ and K̂ cost a few more.
///
/// GMRES works on A itself, nonsymmetric or not, so the solve is as exact as its tolerance:
/// ‖b − A x‖ ≤ tolerance ‖b‖, checked on the true residual.

#include <memory>

#include "gipsi/base/export.h"
#include "gipsi/numerics/sparse/linear_solver.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable or movable (a LinearSolver).
class SaddlePointSolver final : public LinearSolver {
 public:
  /// `num_primary`: n_u; `schur`: Ŝ (square, the pressures' count, symmetric positive
  /// definite, both triangles stored); `options`: the GMRES tolerance and iteration budget
  /// (type "schur_gmres"). Throws InputError if Ŝ cannot be factorised.
  SaddlePointSolver(Index num_primary, const SparseMatrix& schur,
                    const LinearSolverOptions& options);
  ~SaddlePointSolver() override;

  [[nodiscard]] std::string name() const override { return "schur_gmres"; }
  /// Always: the saddle point is indefinite by construction.
  bool AcceptIndefinite() override { return true; }
  /// New values of Ŝ (same pattern as given at construction), factorised by the next
  /// Factorize: a Schur approximation that follows the tangent (a stiffening law).
  void UpdateSchur(const SparseMatrix& schur);
  /// Values added to K̂ (symmetric, at A's positions; the displacement block is read), e.g. an
  /// augmentation γ Bᵀ-like term that makes K̂ definite where the pressure's terms leave K
  /// indefinite; read by every Factorize while set (null: none). Must outlive the solves.
  void SetPrimaryAugmentation(const double* values) { augmentation_ = values; }
  void AnalyzePattern(const SparseMatrix& A) override;
  /// Forms K̂ and B from A and factorises K̂; false if A is not finite or K̂ is singular.
  [[nodiscard]] bool Factorize(const SparseMatrix& A) override;
  /// GMRES from x = 0 (the initial guess is ignored: a Newton correction has no good one).
  LinearSolveStats Solve(const VecX& b, VecX& x) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  const double* augmentation_ = nullptr;
};

}  // namespace gipsi
GIPSI_EXPORT_END
