// Direct sparse solvers: Eigen's simplicial LDLᵀ, CHOLMOD's supernodal LLᵀ (with an LDLᵀ
// fallback for accepted indefinite matrices) and UMFPACK's LU with pivoting, behind one
// base class that owns the shared bookkeeping and the honest residual check.

#include <cmath>
#include <limits>
#include <string>

#include <Eigen/CholmodSupport>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/UmfPackSupport>

#include "gipsi/base/error.h"
#include "gipsi/numerics/sparse/blas_threads.h"
#include "gipsi/numerics/sparse/serial_openmp.h"
#include "gipsi/numerics/sparse/solvers.h"
#include "gipsi/numerics/sparse/supernodal_solve.h"
#include "gipsi/numerics/sparse/vector_ops.h"

namespace gipsi {
namespace {

/// Symbolic analysis once per pattern, numeric factorisation per Factorize, and a Solve that
/// ignores the initial guess and measures ‖b − A x‖ / ‖b‖ with one SpMV. `converged` means
/// the factorisation succeeded, x is finite and the relative residual is ≤ options.tolerance.
class DirectSolver : public LinearSolver {
 public:
  explicit DirectSolver(const LinearSolverOptions& options) : options_(options) {}

  void AnalyzePattern(const SparseMatrix& A) final {
    GIPSI_CHECK(A.rows() == A.cols() && A.isCompressed(),
                "{} AnalyzePattern: matrix must be square and compressed", name());
    rows_ = A.rows();
    nonzeros_ = A.nonZeros();
    analysed_ = true;
    matrix_ = nullptr;
    residual_.setZero(rows_);
    Analyze(A);
  }

  [[nodiscard]] bool Factorize(const SparseMatrix& A) final {
    if (!analysed_) AnalyzePattern(A);
    CheckAnalysedShape(A, rows_, nonzeros_, "direct solver Factorize");
    matrix_ = nullptr;
    refactorized_ = false;
    if (!AllValuesFinite(A)) return false;
    refactorized_ = true;
    if (!FactorizeNumeric(A)) return false;
    matrix_ = &A;
    return true;
  }

  LinearSolveStats Solve(const VecX& b, VecX& x) final {
    LinearSolveStats stats;
    stats.refactorized = refactorized_;
    stats.relative_residual = std::numeric_limits<double>::infinity();
    if (matrix_ == nullptr) return stats;  // no successful Factorize
    GIPSI_CHECK(b.size() == rows_, "{} Solve: b has size {}, matrix has {} rows", name(), b.size(),
                rows_);
    const double b_norm = std::sqrt(ParallelDot(b, b, scratch_));
    if (b_norm == 0.0) {
      x.setZero(rows_);
      stats.converged = true;
      stats.relative_residual = 0.0;
      return stats;
    }
    if (!std::isfinite(b_norm) || !SolveInto(b, x)) return stats;
    Multiply(*matrix_, x, residual_);
    const double* __restrict pb = b.data();
    double* __restrict pr = residual_.data();
    const double rr = DeterministicParallelSum(rows_, scratch_, [=](Index begin, Index end) {
      double s = 0.0;
      for (Index i = begin; i < end; ++i) {
        pr[i] = pb[i] - pr[i];
        s += pr[i] * pr[i];
      }
      return s;
    });
    stats.relative_residual = std::sqrt(rr) / b_norm;
    stats.converged =
        std::isfinite(stats.relative_residual) && stats.relative_residual <= options_.tolerance;
    return stats;
  }

 protected:
  /// Symbolic analysis for A's pattern.
  virtual void Analyze(const SparseMatrix& A) = 0;
  /// Numeric factorisation; false if A is not (numerically) positive definite.
  virtual bool FactorizeNumeric(const SparseMatrix& A) = 0;
  /// x = A⁻¹ b with the current factorisation; false on failure.
  virtual bool SolveInto(const VecX& b, VecX& x) = 0;
  /// y = A x for the residual check; the default is for symmetric A (stored in full).
  virtual void Multiply(const SparseMatrix& A, const VecX& x, VecX& y) const {
    SymmetricSpMV(A, x, y);
  }

 private:
  LinearSolverOptions options_;
  Index rows_ = 0;
  Index nonzeros_ = 0;
  bool analysed_ = false;
  const SparseMatrix* matrix_ = nullptr;  ///< the last successfully factorised A
  bool refactorized_ = false;
  VecX residual_;
  ReductionScratch scratch_;
};

/// Eigen SimplicialLDLT with AMD ordering. LDLᵀ itself accepts indefinite matrices, so
/// FactorizeNumeric also requires every pivot D_ii > 0 (a non-positive pivot means A is not
/// positive definite, or is numerically singular) unless AcceptIndefinite was called; then it
/// only requires pivots away from zero (no pivoting: fine for the mildly indefinite tangents of
/// pressure-loaded solids whose volume is constrained, not for saddle-point systems).
class LdltSolver final : public DirectSolver {
 public:
  using DirectSolver::DirectSolver;
  [[nodiscard]] std::string name() const override { return "ldlt"; }
  bool AcceptIndefinite() override {
    indefinite_ = true;
    return true;
  }

 protected:
  void Analyze(const SparseMatrix& A) override { ldlt_.analyzePattern(A); }
  bool FactorizeNumeric(const SparseMatrix& A) override {
    ldlt_.factorize(A);
    if (ldlt_.info() != Eigen::Success) return false;
    const VecX& d = ldlt_.vectorD();
    if (!indefinite_) return (d.array() > 0.0).all();
    return d.allFinite() && d.cwiseAbs().minCoeff() > 1e-13 * d.cwiseAbs().maxCoeff();
  }
  bool SolveInto(const VecX& b, VecX& x) override {
    x = ldlt_.solve(b);
    return ldlt_.info() == Eigen::Success;
  }

 private:
  Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt_;
  bool indefinite_ = false;
};

/// Eigen's CHOLMOD supernodal LLᵀ with its factor in reach (for SupernodalSolve).
class CholmodLlt final : public Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> {
 public:
  /// The factor as SupernodalSolve reads it; false if it is not a real double supernodal LLᵀ
  /// with int indices (then CHOLMOD's own solve is used).
  bool View(SupernodalFactorView& view) const {
    const cholmod_factor* L = m_cholmodFactor;
    if (L == nullptr || !L->is_super || !L->is_ll || L->itype != CHOLMOD_INT ||
        L->xtype != CHOLMOD_REAL || L->dtype != CHOLMOD_DOUBLE || L->x == nullptr)
      return false;
    view.n = static_cast<int>(L->n);
    view.nsuper = static_cast<int>(L->nsuper);
    view.super = static_cast<const int*>(L->super);
    view.pi = static_cast<const int*>(L->pi);
    view.px = static_cast<const int*>(L->px);
    view.s_rows = static_cast<const int*>(L->s);
    view.values = static_cast<const double*>(L->x);
    view.perm = static_cast<const int*>(L->Perm);
    return true;
  }
};

/// CHOLMOD supernodal LLᵀ (ordered by AMD or METIS, whichever fills less), solved by
/// SupernodalSolve (the two halves of a nested dissection on two threads).
/// Both read the lower triangle only. After AcceptIndefinite, a matrix that LLᵀ finds not
/// positive definite is factorised by LDLᵀ instead (the simplicial LdltSolver's pivot rule):
/// the tangents of pressure-loaded solids are positive definite most of the time, and the
/// supernodal LLᵀ is several times faster than a simplicial LDLᵀ.
class CholmodSolver final : public DirectSolver {
 public:
  explicit CholmodSolver(const LinearSolverOptions& options) : DirectSolver(options) {
    // CHOLMOD prints "matrix not positive definite" at any print level > 0; Factorize reports
    // it by returning false instead, so keep CHOLMOD quiet.
    llt_.cholmod().print = 0;
    UseSingleThreadedBlasOnce();
  }
  [[nodiscard]] std::string name() const override { return "cholmod"; }
  bool AcceptIndefinite() override {
    indefinite_ = true;
    return true;
  }

 protected:
  void Analyze(const SparseMatrix& A) override {
    const SerialOpenMp serial;
    // Small matrices: coarser supernodes. Each supernode costs CHOLMOD a few OpenMP regions
    // (a futex call each, even inactive) and BLAS calls whatever its size; on the heart's
    // 1,326-row tangent that overhead was half the factorisation. Relaxed amalgamation (more
    // explicit zeros in bigger supernodes; CHOLMOD's defaults are nrelax 4/16/48, zrelax
    // 0.8/0.1/0.05) cut it from 88 to 37 supernodes and the factorisation from 2.2 to 1.4 ms
    // here. Larger matrices gain nothing from it: the 216k-row lattice of bench/sparse_bench
    // factorised 5–8 % slower with it, and the fine heart's 8,529-row tangent (METIS-ordered)
    // 3 % slower (muscle linear solves, three alternating runs), hence the limit.
    cholmod_common& c = llt_.cholmod();
    const bool small = A.rows() <= kSmallRows;
    c.nrelax[0] = small ? 16 : 4;
    c.nrelax[1] = small ? 48 : 16;
    c.nrelax[2] = small ? 128 : 48;
    c.zrelax[0] = 0.8;
    c.zrelax[1] = small ? 0.3 : 0.1;
    c.zrelax[2] = small ? 0.1 : 0.05;
    // Both AMD and METIS's nested dissection; CHOLMOD keeps the one with the fewer nonzeros in
    // L. By default it tries METIS only when AMD fills very badly, which the tangents of
    // shell-like meshes never do: on the 10.9k-tet heart's 8,529-row tangent METIS gives 1.49 M
    // nonzeros and 4.5e8 flops per factorisation against AMD's 1.78 M and 7.2e8, and the
    // muscle's linear solves took 12-22 % less time (docs/performance.md); on the default
    // heart's 1,326 rows the two are within 2 %. Analysed once per pattern.
    c.nmethods = 2;
    c.method[0].ordering = CHOLMOD_AMD;
    c.method[1].ordering = CHOLMOD_METIS;
    llt_.analyzePattern(A);
    ldlt_analysed_ = false;
    solve_analysed_ = false;
  }
  bool FactorizeNumeric(const SparseMatrix& A) override {
    use_ldlt_ = false;
    {
      const SerialOpenMp serial;
      llt_.factorize(A);
    }
    if (llt_.info() == Eigen::Success) return true;
    if (!indefinite_) return false;
    if (!ldlt_analysed_) {
      ldlt_.analyzePattern(A);
      ldlt_analysed_ = true;
    }
    ldlt_.factorize(A);
    if (ldlt_.info() != Eigen::Success) return false;
    const VecX& d = ldlt_.vectorD();
    use_ldlt_ = true;
    return d.allFinite() && d.cwiseAbs().minCoeff() > 1e-13 * d.cwiseAbs().maxCoeff();
  }
  bool SolveInto(const VecX& b, VecX& x) override {
    if (use_ldlt_) {
      x = ldlt_.solve(b);
      return ldlt_.info() == Eigen::Success;
    }
    SupernodalFactorView view;
    if (llt_.View(view)) {
      // The structure is the symbolic analysis's; only the values change per factorisation.
      if (!solve_analysed_) supernodal_.Analyze(view);
      solve_analysed_ = true;
      supernodal_.Solve(view, b, x);
      return true;  // Solve's residual check judges x
    }
    const SerialOpenMp serial;
    x = llt_.solve(b);
    return llt_.info() == Eigen::Success;
  }

 private:
  static constexpr Index kSmallRows = 5000;  ///< relaxed supernodes up to this size
  CholmodLlt llt_;
  SupernodalSolve supernodal_;
  bool solve_analysed_ = false;  // supernodal_ has read the current analysis's structure
  Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt_;
  bool indefinite_ = false;
  bool ldlt_analysed_ = false;
  bool use_ldlt_ = false;  // the last factorisation fell back to LDLᵀ
};

/// UMFPACK LU with threshold partial pivoting (UMFPACK's default strategy, which picks its
/// symmetric mode for a symmetric pattern). The matrices of this interface are symmetric and
/// stored in full, so UMFPACK sees the whole matrix; unlike the LDLᵀ without pivoting it
/// factorises symmetric saddle-point matrices with a zero block (fully incompressible mixed
/// elements), whatever the ordering. Indefinite matrices are always accepted; a singular one
/// fails. Unlike the others it also solves nonsymmetric matrices (of a symmetric pattern, as
/// every matrix here: e.g. the exact tangent of a follower load).
class UmfpackSolver final : public DirectSolver {
 public:
  explicit UmfpackSolver(const LinearSolverOptions& options)
      : DirectSolver(options), tolerance_(options.tolerance) {
    UseSingleThreadedBlasOnce();
    // UMFPACK's own iterative refinement (up to two steps by default) evaluates its backward
    // error after every solve, refined or not: over half of a solve's time on the mixed heart's
    // saddle points. SolveInto refines only when the residual asks for it.
    lu_.umfpackControl()(UMFPACK_IRSTEP) = 0;
  }
  [[nodiscard]] std::string name() const override { return "umfpack"; }
  bool AcceptIndefinite() override { return true; }

 protected:
  void Analyze(const SparseMatrix& A) override {
    const SerialOpenMp serial;
    lu_.analyzePattern(A);
  }
  bool FactorizeNumeric(const SparseMatrix& A) override {
    const SerialOpenMp serial;
    lu_.factorize(A);
    matrix_ = &A;
    // Eigen reports any status but UMFPACK_OK, including UMFPACK_WARNING_singular_matrix (an
    // exactly zero pivot), as a failure; Solve's residual check catches a nearly singular one.
    return lu_.info() == Eigen::Success;
  }
  bool SolveInto(const VecX& b, VecX& x) override {
    const SerialOpenMp serial;
    x = lu_.solve(b);
    if (lu_.info() != Eigen::Success) return false;
    // Refinement x += A⁻¹ (b − A x) while the residual is above a hundredth of the tolerance
    // (at most two steps, as UMFPACK would): rare with threshold pivoting.
    const double target = 0.01 * tolerance_ * b.norm();
    for (int step = 0; step < 2; ++step) {
      correction_.noalias() = *matrix_ * x;
      correction_ = b - correction_;
      if (!(correction_.norm() > target)) break;
      x += lu_.solve(correction_);
      if (lu_.info() != Eigen::Success) return false;
    }
    return true;
  }
  void Multiply(const SparseMatrix& A, const VecX& x, VecX& y) const override {
    y.noalias() = A * x;
  }

 private:
  Eigen::UmfPackLU<SparseMatrix> lu_;
  double tolerance_;
  const SparseMatrix* matrix_ = nullptr;  // the factorised matrix (alive while it is used)
  VecX correction_;
};

}  // namespace

std::unique_ptr<LinearSolver> MakeUmfpackSolver(const LinearSolverOptions& options) {
  return std::make_unique<UmfpackSolver>(options);
}

std::unique_ptr<LinearSolver> MakeLdltSolver(const LinearSolverOptions& options) {
  return std::make_unique<LdltSolver>(options);
}

std::unique_ptr<LinearSolver> MakeCholmodSolver(const LinearSolverOptions& options) {
  return std::make_unique<CholmodSolver>(options);
}

}  // namespace gipsi
