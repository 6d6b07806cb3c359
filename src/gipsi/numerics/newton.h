#pragma once
/// @file
/// Newton's method with a backtracking line search for sparse nonlinear systems r(d) = 0 whose
/// Jacobian is symmetric positive definite near the solution (implicit mechanics). The system
/// evaluates residuals and assembles Jacobians in place; the solver owns nothing but work
/// vectors and a LinearSolver, so a step allocates nothing after `Prepare`.
///
/// Iteration k: solve J(d_k) Δ = −r(d_k); take d_{k+1} = d_k + α Δ with α = 1, ½, ¼, … until
/// ‖r(d_{k+1})‖ ≤ (1 − c α) ‖r(d_k)‖ (Armijo on the residual norm; c = 1e-4) and the trial state
/// is admissible (e.g. no inverted element for laws defined only for det F > 0). Converged when
/// ‖r‖ ≤ max(tolerance · max(‖r(d_0)‖, force_scale), residual_floor) or
/// ‖Δ‖∞ ≤ max(increment_tolerance, relative_increment_tolerance · ‖d‖∞).

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "gipsi/base/math.h"
#include "gipsi/numerics/sparse/linear_solver.h"

namespace gipsi {

class StateReader;
class StateWriter;

/// What Newton needs from a problem. Implementations must not allocate or throw.
class NonlinearSystem {
 public:
  virtual ~NonlinearSystem() = default;
  /// Residual r(d); returns false if d is not admissible (r unspecified).
  virtual bool CalcResidual(const VecX& d, VecX& r) = 0;
  /// Residual and Jacobian at d (J keeps its sparsity pattern); false if not admissible.
  virtual bool CalcResidualAndJacobian(const VecX& d, VecX& r, SparseMatrix& J) = 0;
  /// A force scale for the convergence test (e.g. ‖f_ext‖ + ‖M a‖), ≥ 0.
  [[nodiscard]] virtual double force_scale() const { return 0; }
  /// The round-off floor of the last residual evaluated (e.g. a small multiple of machine
  /// epsilon times the sum of the magnitudes of the terms assembled into it), ≥ 0: no iterate
  /// can be told apart from the solution below it, so Newton accepts a residual under it.
  [[nodiscard]] virtual double residual_floor() const { return 0; }
  /// Optional low-rank part of the Jacobian kept out of the sparse matrix because it is dense
  /// (e.g. a cavity's volume gradient times its pressure–volume stiffness): the full Jacobian
  /// is J + Σ_k w_k b_k b_kᵀ with w_k ≥ 0, valid after the last CalcResidualAndJacobian.
  /// Newton solves with it by the Sherman–Morrison–Woodbury formula (one extra solve with J per
  /// term). Default: none.
  [[nodiscard]] virtual int num_low_rank_terms() const { return 0; }
  /// Term k (k < 8): sets `b` (size of the system, zero on constrained unknowns) and `w`.
  virtual void LowRankTerm(int /*k*/, const VecX*& /*b*/, double& /*w*/) const {}
};

/// Options. Plain struct.
struct NewtonOptions {
  int max_iterations = 25;
  double tolerance = 1e-8;         ///< relative residual
  double increment_tolerance = 0;  ///< absolute ‖Δ‖∞ [m]; 0 disables
  /// Also converged when the full Newton correction is this small relative to the iterate,
  /// ‖Δ‖∞ ≤ relative_increment_tolerance · ‖d‖∞ (the residual has reached its round-off floor
  /// and further iterations cannot move the solution); 0 disables.
  double relative_increment_tolerance = 1e-11;
  bool line_search = true;
  int max_line_search_steps = 12;
  /// Interactive mode: take exactly max_iterations iterations and accept the result (the usual
  /// one-Newton-step-per-frame practice); the residual is then not recomputed.
  bool fixed_iterations = false;
  /// Start the first linear solve of each Solve from the previous Solve's first correction
  /// (iterative solvers converge faster when consecutive steps are alike).
  bool warm_start = true;
  /// Keep the factorised Jacobian (of an earlier iteration, or of the previous Solve) while it
  /// still works: a new Jacobian is assembled and factorised only when an iteration reduced the
  /// residual by less than half, or a solve or line search with the old one failed. Newton
  /// then converges linearly but each iteration costs a residual and a back-substitution
  /// instead of an assembly and a factorisation — a large gain with direct solvers on
  /// slowly varying problems (a beating heart). Needs the Jacobian matrix left untouched
  /// between Solves (the system only writes it in CalcResidualAndJacobian).
  bool reuse_factorization = false;
};

/// Outcome of one solve. Plain struct.
struct NewtonStats {
  bool converged = false;
  bool inadmissible = false;  ///< stopped because no admissible state was found
  bool linear_failure = false;
  int iterations = 0;
  int linear_iterations = 0;
  int refactorizations = 0;
  double initial_residual = 0;
  double final_residual = 0;
  static constexpr int kHistory = 8;
  std::array<double, kHistory> residual_history{};  ///< first ‖r‖ values (for diagnostics)
};

/// Not copyable.
class NewtonSolver {
 public:
  NewtonSolver(NewtonOptions options, std::unique_ptr<LinearSolver> linear);
  NewtonSolver(const NewtonSolver&) = delete;
  NewtonSolver& operator=(const NewtonSolver&) = delete;

  /// Sizes work vectors and analyses J's pattern once.
  void Prepare(const SparseMatrix& pattern);
  /// Solves r(d) = 0 starting from d (in: initial guess; out: the last accepted iterate).
  /// `J` is the matrix the system assembles into (the pattern given to Prepare).
  NewtonStats Solve(NonlinearSystem& system, VecX& d, SparseMatrix& J);

  [[nodiscard]] const NewtonOptions& options() const { return options_; }
  [[nodiscard]] LinearSolver& linear_solver() { return *linear_; }
  /// The residual at the last accepted iterate (valid unless fixed_iterations).
  [[nodiscard]] const VecX& residual() const { return r_; }
  /// Checkpoints (gipsi/base/state.h): what one Solve hands to the next — the warm start and,
  /// with reuse_factorization, whether a factorisation is kept and the values of `J`, the
  /// matrix given to Solve (it holds the factorised values then). RestoreState writes the
  /// values back into `J` (same pattern) and factorises it again (deterministic: the same
  /// factors), so a resumed run iterates exactly like an uninterrupted one.
  void SaveState(StateWriter& out, const SparseMatrix& J) const;
  void RestoreState(StateReader& in, SparseMatrix& J);

 private:
  NewtonOptions options_;
  std::unique_ptr<LinearSolver> linear_;
  VecX r_, r_trial_, delta_, d_trial_, rhs_;
  VecX warm_;  // first correction of the last solve
  bool warm_valid_ = false;
  bool factor_valid_ = false;  // the linear solver holds a factorisation of the current J
  static constexpr int kMaxLowRankTerms = 8;
  std::vector<VecX> low_rank_z_;  // J⁻¹ b_k of the low-rank terms (sized on first use)

  /// Applies the low-rank correction to delta_ = J⁻¹ rhs (Woodbury); false if a solve fails.
  bool ApplyLowRank(NonlinearSystem& system, NewtonStats& stats);
};

/// One-line summary of a failed solve for diagnostics ("Newton did not converge in 25
/// iterations: |r| 3.1e+02 -> 4.5e-03 (tolerance 1e-08) ...").
std::string Describe(const NewtonStats& stats, const NewtonOptions& options);

}  // namespace gipsi
