#pragma once
/// @file
/// Newton's method with a globalised step for sparse nonlinear systems r(d) = 0 whose Jacobian
/// is symmetric and, near the solution, positive definite (implicit mechanics). The system
/// evaluates residuals and assembles Jacobians in place; the solver owns nothing but work
/// vectors and a LinearSolver, so a step allocates nothing after `Prepare`.
///
/// Iteration k: solve J(d_k) Δ = −r(d_k); take d_{k+1} = d_k + α Δ with α = 1, ½, ¼, … until
/// the trial state is admissible (e.g. no inverted element) and makes progress by one of two
/// merits:
///   1. the residual norm (Armijo, c = 1e-4): ‖r(d_k + αΔ)‖ ≤ (1 − c α) ‖r(d_k)‖; or
///   2. the natural monotonicity test on the increment (Deuflhard, "Newton Methods for
///      Nonlinear Problems", Springer 2004, §3.3, the test of NLEQ-ERR): the simplified Newton
///      correction with the same factorisation, Δ̄ = −J(d_k)⁻¹ r(d_k + αΔ), satisfies
///      ‖Δ̄‖ ≤ (1 − α/4) ‖Δ‖.
/// The second is affine covariant: it measures progress in the unknowns, not in the residual,
/// so it accepts the full step of a nearly incompressible solid whose residual jumps by
/// orders of magnitude in the stiff volumetric modes while the iterate is already in the
/// region of quadratic convergence (a residual-only line search cuts such a step to 1/4096
/// and stalls). It costs one more solve with the factorised J, taken only when the residual
/// test fails.
///
/// Converged when ‖r‖ ≤ max(tolerance · max(‖r(d_0)‖, force_scale), absolute_tolerance,
/// residual_floor) or the full correction is small: ‖Δ‖∞ ≤ max(increment_tolerance,
/// relative_increment_tolerance · ‖d‖∞). An iteration budget that runs out while the solve is
/// converging (each of the last two iterations contracted by at least half) is extended, up to
/// twice `max_iterations`: a converging solve is not abandoned (and then bisected by its
/// caller) one iteration before it would converge.

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/base/state_value.h"
#include "gipsi/base/stop_token.h"
#include "gipsi/numerics/sparse/linear_solver.h"

GIPSI_EXPORT_BEGIN
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
  /// Term k (k < 8): sets `b` (size of the sparse system, zero on constrained unknowns) and
  /// `w`.
  virtual void LowRankTerm(int /*k*/, const VecX*& /*b*/, double& /*w*/) const {}
  /// Bordered scalar unknowns (e.g. cavity pressures solved with the wall), one per low-rank
  /// term when not 0: the iterate is then (u, q) with q_k appended after the n sparse unknowns,
  /// and the residual (r_u, r_q) with
  ///   ∂r_u/∂u = J,  ∂r_u/∂q_k = −b_k,  ∂r_q,k/∂u = b_kᵀ,  ∂r_q,k/∂q_k = 1/w_k  (w_k > 0).
  /// Newton eliminates q: (J + Σ w_k b_k b_kᵀ) Δu = −r_u − Σ w_k r_q,k b_k (the low-rank terms
  /// above, by Woodbury), then Δq_k = −w_k (r_q,k + b_kᵀ Δu). Unlike a q(u) solved inside the
  /// residual (a penalty with weight w_k), a stiff w_k then does not amplify the quadratic
  /// error of a step in r_q into r_u, so Newton keeps its quadratic convergence however stiff
  /// the coupling. Convergence is tested on ‖(r_u, w_k ‖b_k‖ r_q,k)‖, the residual r_u would
  /// have with each q_k moved to zero r_q,k; the line search accepts a step that reduces that
  /// norm or ‖r_u‖ (a step that repairs r_q may raise r_u, and a step that reduces r_u may leave
  /// a volume error that w_k magnifies).
  /// Must not change between Prepare and Solve; a term with w_k ≤ 0 (q_k not determined) fails
  /// the iteration's linear solve.
  [[nodiscard]] virtual int num_bordered() const { return 0; }
};

/// How Newton measures vectors of a system split over processes (a FemSolid on one MPI rank's
/// part of a mesh, parallel/distributed_solid.h). Each process holds its share of the sparse
/// unknowns, the first `owned()` entries, followed by copies of entries other processes own;
/// bordered unknowns (after the sparse ones) are the same on every process. Norms and dot
/// products then count each sparse unknown once, on its owner. Implementations are collective:
/// every process must call them in the same order (they do: every decision Newton takes rests
/// on these reductions, so all processes take the same).
class VectorReduction {
 public:
  virtual ~VectorReduction() = default;
  /// The entries of the sparse part this process owns (its leading ones).
  [[nodiscard]] virtual Index owned() const = 0;
  /// Replaces every value by its sum (`max` false) or maximum over the processes.
  virtual void Reduce(std::span<double> values, bool max) const = 0;
};

/// Options. Plain struct. The defaults are the stated defaults of the scene key "newton".
struct NewtonOptions {
  /// Iteration budget; extended up to twice this while the solve is converging.
  int max_iterations = 25;
  /// Relative residual tolerance: converged when ‖r‖ ≤ tolerance · max(‖r(d_0)‖,
  /// force_scale) (the system's applied-load scale).
  double tolerance = 1e-8;
  /// Absolute residual tolerance [the residual's unit, N for mechanics]: also converged when
  /// ‖r‖ ≤ absolute_tolerance. 0 disables (the system's round-off floor still applies).
  double absolute_tolerance = 0;
  double increment_tolerance = 0;  ///< absolute ‖Δ‖∞ [m]; 0 disables
  /// Also converged when the full Newton correction is this small relative to the iterate,
  /// ‖Δ‖∞ ≤ relative_increment_tolerance · ‖d‖∞ (the residual has reached its round-off floor
  /// and further iterations cannot move the solution); 0 disables.
  double relative_increment_tolerance = 1e-11;
  /// Globalise the step (the residual and natural-monotonicity tests above); false takes full
  /// Newton steps whatever they do (as long as the state stays admissible).
  bool line_search = true;
  /// Accept a trial step by the natural monotonicity test when the residual test fails (one
  /// extra solve with the factorised Jacobian per such trial). false: residual test only.
  /// Not applied to systems with low-rank Jacobian terms (a cavity coupled to blood): on a
  /// stiff isovolumetric step it accepted steps that then stagnated at ‖r‖ ≈ 3e-8, above the
  /// tolerance (CavityCoupling.IsovolumetricContractionThenEjection); not investigated further.
  bool monotonicity_test = true;
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
  /// With reuse_factorization: Anderson acceleration of the iterations that reuse a kept
  /// factorisation, with the differences of the last `anderson` iterates (0 = off, at most 8).
  /// The iteration with a kept factor is the fixed point x ← x + Δ(x), Δ = −Ĵ⁻¹ r(x) (Ĵ: the
  /// kept, older tangent), which converges linearly. Anderson's type-II mixing (Walker & Ni,
  /// SIAM J. Numer. Anal. 49, 2011) steps from the combination of the last corrections whose
  /// linearised correction is smallest in the least-squares sense: on a linear problem, with the
  /// whole history, essentially GMRES preconditioned by Ĵ. The accelerated step is tried first and
  /// kept if it lowers ‖r‖ (Armijo); otherwise the plain step is taken and the history restarts.
  /// The history belongs to the factorisation: cleared when it is replaced, kept across Solves (and
  /// in checkpoints) while it is kept. On the fine heart it saves a fifth of the iterations and a
  /// sixth of the factorisations (docs/newton.md).
  int anderson = 5;
};

/// Why a linear solve failed. Plain enum.
enum class LinearFailure : std::uint8_t {
  kNone,
  kNotPositiveDefinite,  ///< an SPD-only factorisation refused the tangent (indefinite?)
  kSingular,             ///< refused even by the indefinite (LDLᵀ) factorisation
  kNotConverged,         ///< an iterative solve missed its tolerance or gave non-finite values
};

/// Outcome of one solve. Plain struct, trivially copyable.
struct NewtonStats {
  bool converged = false;
  bool inadmissible = false;  ///< stopped because no admissible state was found
  bool linear_failure = false;
  bool interrupted = false;  ///< a stop was requested (StopToken) before convergence
  /// This solve switched the direct solver to its indefinite (LDLᵀ) mode, for good: the tangent
  /// was not positive definite (the object says so once, with its name and time).
  bool switched_to_indefinite = false;
  LinearFailure linear_failure_kind = LinearFailure::kNone;
  int iterations = 0;
  int linear_iterations = 0;
  int refactorizations = 0;
  /// Iterations whose full step was accepted by the natural monotonicity test although the
  /// residual grew (the case a residual-only line search would have cut).
  int monotonicity_accepts = 0;
  int backtracks = 0;  ///< step halvings in the line search, over all iterations
  /// Iterations whose Anderson-accelerated step was accepted, and tried but refused
  /// (NewtonOptions::anderson).
  int anderson_accepts = 0;
  int anderson_rejects = 0;
  double initial_residual = 0;
  double final_residual = 0;
  static constexpr int kHistory = 8;
  std::array<double, kHistory> residual_history{};  ///< first ‖r‖ values (for diagnostics)

  /// State value fields (gipsi/base/state_value.h): an object keeps its last statistics as
  /// state (failure messages and profiles read them).
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("converged", s.converged);
    v("inadmissible", s.inadmissible);
    v("linear_failure", s.linear_failure);
    v("interrupted", s.interrupted);
    v("switched_to_indefinite", s.switched_to_indefinite);
    v("linear_failure_kind", s.linear_failure_kind);
    v("iterations", s.iterations);
    v("linear_iterations", s.linear_iterations);
    v("refactorizations", s.refactorizations);
    v("monotonicity_accepts", s.monotonicity_accepts);
    v("backtracks", s.backtracks);
    v("anderson_accepts", s.anderson_accepts);
    v("anderson_rejects", s.anderson_rejects);
    v("initial_residual", s.initial_residual);
    v("final_residual", s.final_residual);
    v("residual_history", s.residual_history, Shape::kFixed);
  }
};

/// Not copyable.
class NewtonSolver {
 public:
  NewtonSolver(NewtonOptions options, std::unique_ptr<LinearSolver> linear);
  NewtonSolver(const NewtonSolver&) = delete;
  NewtonSolver& operator=(const NewtonSolver&) = delete;

  /// Sizes work vectors and analyses J's pattern once; `bordered`: the system's
  /// num_bordered() (the iterate has pattern.rows() + bordered entries).
  void Prepare(const SparseMatrix& pattern, int bordered = 0);
  /// Solves r(d) = 0 starting from d (in: initial guess; out: the last accepted iterate).
  /// `J` is the matrix the system assembles into (the pattern given to Prepare).
  /// Polls `stop` at the start of every iteration and before every line-search trial: when a
  /// stop is requested it returns at once with `interrupted` set and d at the last accepted
  /// iterate (not converged).
  NewtonStats Solve(NonlinearSystem& system, VecX& d, SparseMatrix& J, StopToken stop = {});

  /// Measures vectors with `reduction` (not owned; null: this process holds the whole system,
  /// the default). Set before Prepare. The linear solver must then be one that solves the
  /// split system (its vectors laid out the same way).
  void SetReduction(const VectorReduction* reduction) { reduction_ = reduction; }
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
  /// Forgets what one Solve hands to the next (the warm start and the kept factorisation), so
  /// the next Solve starts cold and factorises at its first iterate: after the owner returned
  /// to an earlier state (a snapshot), whose future these belonged to.
  void ForgetHandOver() {
    warm_valid_ = false;
    factor_valid_ = false;
    low_rank_kept_ = false;
    ClearAnderson();
  }

 private:
  NewtonOptions options_;
  std::unique_ptr<LinearSolver> linear_;
  const VectorReduction* reduction_ = nullptr;
  VecX r_, r_trial_, delta_, d_trial_, rhs_, simplified_;
  Index sparse_size_ = 0;           // n: the iterate's unknowns in J (then num_bordered() scalars)
  VecX bordered_rhs_, bordered_x_;  // the sparse part of a bordered system's correction
  VecX warm_;                       // first correction of the last solve
  bool warm_valid_ = false;
  bool factor_valid_ = false;  // the linear solver holds a factorisation of the current J
  bool indefinite_ = false;    // the linear solver was switched to its indefinite mode
  static constexpr int kMaxLowRankTerms = 8;
  static constexpr int kMaxAnderson = 8;
  std::vector<VecX> low_rank_z_;  // J⁻¹ b_k of the low-rank terms (sized on first use)
  // With bordered unknowns the b_k are kept with the factorisation, like J: a kept
  // factorisation then costs one solve per iteration instead of 1 + num_low_rank_terms (the
  // residual stays exact, so Newton converges to the same solution).
  std::vector<VecX> low_rank_b_;
  bool low_rank_kept_ = false;  // low_rank_b_ and low_rank_z_ belong to the factorisation
  // Anderson acceleration (NewtonOptions::anderson): the differences of the last iterates and
  // of their corrections with the current factorisation (columns of a ring), the last iterate
  // and correction, and the accelerated step.
  Eigen::MatrixXd aa_dx_, aa_df_;
  VecX aa_x_, aa_f_, aa_step_;
  int aa_count_ = 0;  // valid columns
  int aa_head_ = 0;   // next column to write
  bool aa_prev_ = false;

  /// The correction delta_ = −J⁻¹ r_ with the low-rank terms and bordered unknowns, started
  /// from warm_ if `warm`; false if the linear solve fails (`ls` tells how).
  bool SolveCorrection(NonlinearSystem& system, NewtonStats& stats, bool warm,
                       LinearSolveStats& ls);
  /// ‖r_u‖ (the line search's merit) and the convergence norm of r (the same without
  /// bordered unknowns; see NonlinearSystem::num_bordered).
  [[nodiscard]] double Norms(const NonlinearSystem& system, const VecX& r, double& merit) const;
  /// a·b over the first n entries, ‖a‖ (every entry: the sparse ones then the bordered ones)
  /// and ‖a‖∞, each unknown counted once (VectorReduction); Eigen's own with no reduction.
  [[nodiscard]] double Dot(Eigen::Ref<const VecX> a, Eigen::Ref<const VecX> b, Index n) const;
  [[nodiscard]] double Norm(const VecX& a) const;
  [[nodiscard]] double NormInf(const VecX& a) const;
  /// Whether every process's `ok` is true.
  [[nodiscard]] bool All(bool ok) const;
  /// Applies the low-rank terms to x = J⁻¹ rhs (Woodbury); false if a solve fails. `kept`:
  /// with the b_k and J⁻¹ b_k kept with the factorisation (KeepLowRank).
  bool ApplyLowRank(NonlinearSystem& system, NewtonStats& stats, VecX& x, bool kept = false);
  /// Keeps the system's current b_k and solves J⁻¹ b_k with the current factorisation.
  bool KeepLowRank(NonlinearSystem& system, NewtonStats& stats);
  bool SolveLowRankZ(const VecX& b, VecX& z, NewtonStats& stats);
  static double LowRankWeight(const NonlinearSystem& system, int k);
  /// The natural monotonicity test of trial step α: true if ‖J⁻¹ r_trial_‖ ≤ (1 − α/4) ‖Δ‖.
  bool Monotone(NonlinearSystem& system, NewtonStats& stats, double alpha);
  /// Records the iterate d and its correction delta_ in the Anderson history; with history,
  /// sets aa_step_ to the accelerated step and returns true.
  bool AndersonStep(const VecX& d);
  void ClearAnderson() {
    aa_count_ = aa_head_ = 0;
    aa_prev_ = false;
  }
  /// Factorises J; on failure of an SPD-only direct solver, switches it to its indefinite
  /// (LDLᵀ) mode once and retries. Sets the failure kind.
  bool FactorizeTangent(const SparseMatrix& J, NewtonStats& stats);
};

/// Summary of a failed solve for diagnostics: what failed, the residual history, and for a
/// tangent that could not be factorised, with which solver (`solver`, e.g. "cholmod") and
/// what to try.
std::string Describe(const NewtonStats& stats, const NewtonOptions& options,
                     std::string_view solver = {});

}  // namespace gipsi
GIPSI_EXPORT_END
