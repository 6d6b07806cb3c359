// Preconditioned conjugate gradients with a warm start, a stopping rule on the true residual,
// and six preconditioners (none, Jacobi, symmetric block Gauss-Seidel, incomplete Cholesky,
// lagged CHOLMOD Cholesky, smoothed-aggregation AMG with a lagged hierarchy).

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/CholmodSupport>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/OrderingMethods>

#include "gipsi/base/error.h"
#include "gipsi/numerics/adaptive_parallel.h"
#include "gipsi/numerics/sparse/amg.h"
#include "gipsi/numerics/sparse/cg_kernels.h"
#include "gipsi/numerics/sparse/node_block_copy.h"
#include "gipsi/numerics/sparse/node_block_sgs.h"
#include "gipsi/numerics/sparse/serial_openmp.h"
#include "gipsi/numerics/sparse/solvers.h"
#include "gipsi/numerics/sparse/team_barrier.h"
#include "gipsi/numerics/sparse/vector_ops.h"

namespace gipsi {
namespace {

enum class Preconditioner { kNone, kJacobi, kSgs, kIncompleteCholesky, kLaggedCholesky, kAmg };

Preconditioner PreconditionerFromName(const std::string& name) {
  if (name == "none") return Preconditioner::kNone;
  if (name == "jacobi") return Preconditioner::kJacobi;
  if (name == "sgs") return Preconditioner::kSgs;
  if (name == "ic") return Preconditioner::kIncompleteCholesky;
  if (name == "amg") return Preconditioner::kAmg;
  GIPSI_CHECK(name == "cholesky", "MakePcgSolver: unvalidated preconditioner '{}'", name);
  return Preconditioner::kLaggedCholesky;
}

/// The CG iteration proper works on the recursively updated residual; Solve confirms every
/// claimed convergence on the true residual b − A x and restarts CG from it if the two
/// disagree (residual replacement), so the reported residual is always the true one.
class PcgSolver final : public LinearSolver {
 public:
  explicit PcgSolver(const LinearSolverOptions& options)
      : options_(options), kind_(PreconditionerFromName(options.preconditioner)) {
    // CHOLMOD prints even "matrix not positive definite" as an error at any print level > 0;
    // Factorize reports failures through its return value instead, so keep CHOLMOD quiet.
    cholesky_.cholmod().print = 0;
  }

  [[nodiscard]] std::string name() const override { return "cg+" + options_.preconditioner; }

  void SetNearNullSpace(const Eigen::MatrixXd& modes) override {
    if (kind_ == Preconditioner::kAmg) amg_.SetNearNullSpace(modes);
  }

  void AnalyzePattern(const SparseMatrix& A) override {
    GIPSI_CHECK(A.rows() == A.cols() && A.isCompressed(),
                "PCG AnalyzePattern: matrix must be square and compressed");
    rows_ = A.rows();
    nonzeros_ = A.nonZeros();
    node_blocks_ = HasNodeBlockPattern(A);
    diagonal_index_.clear();  // found again by the next ComputeInverseDiagonal
    // The fused CG multiplies by a block-row copy of a node-block matrix (node_block_copy.h).
    block_copy_ready_ = false;
    if (node_blocks_ && fused() && !sgs()) block_copy_.AssignPattern(A);
    if (sgs()) sgs_.AssignPattern(A, SgsDomainCount(rows_));
    analysed_ = true;
    matrix_ = nullptr;
    has_factor_ = false;
    refactor_pending_ = false;
    for (VecX* v : {&r_, &z_, &p_, &q_, &w_}) v->setZero(rows_);
    switch (kind_) {
      case Preconditioner::kNone:
        inverse_diagonal_.setOnes(rows_);  // IterateFused scales by it: M = I
        break;
      case Preconditioner::kJacobi:
      case Preconditioner::kSgs:  // Jacobi for a matrix not made of node blocks
        inverse_diagonal_.setZero(rows_);
        break;
      case Preconditioner::kIncompleteCholesky:
        incomplete_.analyzePattern(A);
        break;
      case Preconditioner::kLaggedCholesky: {
        const SerialOpenMp serial;  // serial_openmp.h: CHOLMOD's fixed 4-thread regions
        cholesky_.analyzePattern(A);
        // A factorisation in CG iterations: its flops over one iteration's (two triangular
        // solves, 4 nnz(L), and an SpMV, 2 nnz(A)), halved because the supernodal
        // factorisation does more flops per second than the memory-bound solves (measured on
        // the FEM benchmark: 1.2× at 5k tets, 4.2× at 20k; 2 is within a factor 2 of both).
        const cholmod_common& c = cholesky_.cholmod();
        factor_cost_ = c.fl / (2.0 * (4.0 * c.lnz + 2.0 * static_cast<double>(nonzeros_)));
        if (!std::isfinite(factor_cost_) || factor_cost_ < 1.0) factor_cost_ = 1.0;
        break;
      }
      case Preconditioner::kAmg:
        break;  // the hierarchy depends on the values: built by the first Factorize
    }
  }

  [[nodiscard]] bool Factorize(const SparseMatrix& A) override {
    if (!analysed_) AnalyzePattern(A);
    CheckAnalysedShape(A, rows_, nonzeros_, "PCG Factorize");
    matrix_ = nullptr;
    block_copy_ready_ = false;
    refactorized_ = false;
    if (!AllValuesFinite(A)) return false;
    switch (kind_) {
      case Preconditioner::kNone:
        break;
      case Preconditioner::kJacobi:
        if (!ComputeInverseDiagonal(A)) return false;
        break;
      case Preconditioner::kSgs:  // sgs_ copies the values below
        if (!sgs() && !ComputeInverseDiagonal(A)) return false;
        break;
      case Preconditioner::kIncompleteCholesky:
        incomplete_.factorize(A);
        refactorized_ = true;
        if (incomplete_.info() != Eigen::Success) return false;
        break;
      case Preconditioner::kLaggedCholesky:
        if (!has_factor_ || refactor_pending_) {
          const SerialOpenMp serial;
          cholesky_.factorize(A);  // numeric only: the symbolic analysis is reused
          refactorized_ = true;
          refactor_pending_ = false;
          lagged_solves_ = 0;
          lagged_iterations_ = 0;
          has_factor_ = cholesky_.info() == Eigen::Success;
          if (!has_factor_) return false;
        }
        break;
      case Preconditioner::kAmg:
        if (!has_factor_ || refactor_pending_) {
          refactorized_ = true;
          refactor_pending_ = false;
          has_factor_ = amg_.Setup(A);
          if (!has_factor_) return false;
        } else if (!amg_.Refresh(A)) {
          has_factor_ = false;  // rebuild from the next matrix
          return false;
        }
        break;
    }
    if (node_blocks_ && fused() && !sgs()) {
      block_copy_.CopyValues(A, SetUpOnTeam());
      block_copy_ready_ = true;
    }
    if (sgs() && !sgs_.Factorize(A, SetUpOnTeam())) return false;  // a diagonal block not SPD
    matrix_ = &A;
    return true;
  }

  LinearSolveStats Solve(const VecX& b, VecX& x) override {
    LinearSolveStats stats;
    stats.refactorized = refactorized_;
    if (matrix_ == nullptr) {  // no successful Factorize
      stats.relative_residual = std::numeric_limits<double>::infinity();
      return stats;
    }
    GIPSI_CHECK(b.size() == rows_, "PCG Solve: b has size {}, matrix has {} rows", b.size(), rows_);
    if (x.size() != rows_) x.setZero(rows_);
    const double b_norm = std::sqrt(ParallelDot(b, b, scratch_, SetUpOnTeam()));
    if (b_norm == 0.0) {
      x.setZero();
      stats.converged = true;
      return stats;
    }
    // The fused CG's solve runs on the team or on this thread alone, whichever has been faster
    // per iteration lately (team_choice_; its kernels give the same bits either way).
    const bool adaptive = fused();
    const bool team =
        adaptive && team_choice_.Begin(rows_ >= kMinFusedParallelRows &&
                                       omp_get_max_threads() > 1 && (!sgs() || sgs_.domains() > 1));
    std::optional<SerialOpenMp> alone;
    if (adaptive && !team) alone.emplace();
    double r_norm = std::numeric_limits<double>::quiet_NaN();
    if (std::isfinite(b_norm)) {
      const double target = options_.tolerance * b_norm;
      r_norm = TrueResidual(b, x);
      bool stuck = false;
      for (;;) {
        if (!std::isfinite(r_norm)) break;
        if (r_norm <= target) {
          stats.converged = true;
          break;
        }
        if (stats.iterations >= options_.max_iterations || stuck) break;
        if (sgs())
          stuck = !IterateSgs(target, r_norm, stats.iterations, x, team);
        else
          stuck = fused() ? !IterateFused(target, stats.iterations, x, team)
                          : !Iterate(target, stats.iterations, x);
        r_norm = TrueResidual(b, x);
      }
    }
    stats.relative_residual = r_norm / b_norm;
    if (adaptive) team_choice_.End(std::max(1, stats.iterations));  // per iteration
    if (kind_ == Preconditioner::kLaggedCholesky) {
      // Refactorise when the factor got too weak, or (amortised) when this solve took at least
      // the mean cost per solve since the last factorisation, the factorisation included:
      // k its_k ≥ F + Σ_{i≤k} its_i. With iteration counts that grow as the matrix drifts
      // from the factorised one, the mean first falls and then rises, and it rises exactly
      // when its_k passes it, so this refactorises near the minimum of the mean cost.
      ++lagged_solves_;
      lagged_iterations_ += stats.iterations;
      if (!stats.converged || stats.iterations > options_.refactor_iterations ||
          static_cast<double>(lagged_solves_) * stats.iterations >=
              factor_cost_ + static_cast<double>(lagged_iterations_))
        refactor_pending_ = true;
    }
    if (kind_ == Preconditioner::kAmg) {
      // A fresh hierarchy sets the baseline; the lagged one is rebuilt once CG needs both more
      // than refactor_iterations and more than 1.5 times (plus 2) that baseline.
      if (refactorized_) baseline_iterations_ = stats.iterations;
      if (!stats.converged || (stats.iterations > options_.refactor_iterations &&
                               2 * stats.iterations > 3 * baseline_iterations_ + 4))
        refactor_pending_ = true;
    }
    return stats;
  }

 private:
  /// Whether the set-ups around a fused solve (Jacobi's diagonal, the block copy, the norm of
  /// b) run on the team: as the fused solves have lately (team_choice_), so that beside a busy
  /// neighbour they do not each wait for a descheduled thread. Other kinds: always.
  [[nodiscard]] bool SetUpOnTeam() const { return !fused() || team_choice_.prefers_parallel(); }

  /// inverse_diagonal_ = 1 / diag(A); false if a diagonal entry is missing or ≤ 0 (not SPD).
  /// The diagonal's positions are found once per pattern (diagonal_index_).
  bool ComputeInverseDiagonal(const SparseMatrix& A) {
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    const int n = static_cast<int>(rows_);
    if (static_cast<int>(diagonal_index_.size()) != n) {
      diagonal_index_.assign(static_cast<std::size_t>(n), -1);
      for (int j = 0; j < n; ++j)
        for (int k = outer[j]; k < outer[j + 1]; ++k)
          if (inner[k] == j) diagonal_index_[static_cast<std::size_t>(j)] = k;
    }
    const int* diagonal = diagonal_index_.data();
    const double* values = A.valuePtr();
    double* inverse = inverse_diagonal_.data();
    // Counts the entries that are not positive (an atomic, touched only by a matrix that is
    // not SPD; ForRange takes no reduction clause).
    std::atomic<int> not_positive{0};
    ForRange(0, n, SetUpOnTeam() && n >= kMinParallelLength, [&](int j) {
      const double d = diagonal[j] >= 0 ? values[diagonal[j]] : 0.0;
      if (!(d > 0.0)) not_positive.fetch_add(1, std::memory_order_relaxed);
      inverse[j] = d > 0.0 ? 1.0 / d : 0.0;
    });
    return not_positive.load() == 0;
  }

  /// y = A x: from a block-row copy of A when there is one (the AMG hierarchy's finest level,
  /// the fused CG's block_copy_ or the "sgs" sweeps'; 9 contiguous values per block, faster than
  /// NodeBlockSpMV's three column streams), else NodeBlockSpMV for a matrix of 3×3 node
  /// blocks (an FEM tangent), else SymmetricSpMV. The same values and summation order as
  /// IterateFused's products.
  void Multiply(const VecX& x, VecX& y) {
    if (kind_ == Preconditioner::kAmg && amg_.Multiply(x, y)) return;
    if (block_copy_ready_) {
      block_copy_.Multiply(x, y);
      return;
    }
    if (sgs()) {  // the sweeps' copy of the blocks
      sgs_.Multiply(x, y);
      return;
    }
    if (node_blocks_)
      NodeBlockSpMV(*matrix_, x, y);
    else
      SymmetricSpMV(*matrix_, x, y);
  }

  /// r_ = b − A x; returns ‖r_‖.
  double TrueResidual(const VecX& b, const VecX& x) {
    Multiply(x, q_);
    const double* __restrict pb = b.data();
    const double* __restrict pq = q_.data();
    double* __restrict pr = r_.data();
    return std::sqrt(DeterministicParallelSum(rows_, scratch_, [=](Index begin, Index end) {
      double s = 0.0;
      for (Index i = begin; i < end; ++i) {
        pr[i] = pb[i] - pq[i];
        s += pr[i] * pr[i];
      }
      return s;
    }));
  }

  /// z_ = M⁻¹ r_; returns r_ · z_ (NaN if the preconditioner failed).
  double Precondition() {
    const double* __restrict pr = r_.data();
    double* __restrict pz = z_.data();
    switch (kind_) {
      case Preconditioner::kNone:
        return DeterministicParallelSum(rows_, scratch_, [=](Index begin, Index end) {
          double s = 0.0;
          for (Index i = begin; i < end; ++i) {
            pz[i] = pr[i];
            s += pr[i] * pr[i];
          }
          return s;
        });
      case Preconditioner::kJacobi:
      case Preconditioner::kSgs: {  // (Iterate does not run with "sgs": IterateFused does)
        const double* __restrict pd = inverse_diagonal_.data();
        return DeterministicParallelSum(rows_, scratch_, [=](Index begin, Index end) {
          double s = 0.0;
          for (Index i = begin; i < end; ++i) {
            pz[i] = pd[i] * pr[i];
            s += pr[i] * pz[i];
          }
          return s;
        });
      }
      case Preconditioner::kIncompleteCholesky:
        z_ = incomplete_.solve(r_);
        break;
      case Preconditioner::kLaggedCholesky: {
        const SerialOpenMp serial;
        z_ = cholesky_.solve(r_);
      }
        if (cholesky_.info() != Eigen::Success) return std::numeric_limits<double>::quiet_NaN();
        break;
      case Preconditioner::kAmg:
        amg_.Apply(r_, z_);
        break;
    }
    return ParallelDot(r_, z_, scratch_);
  }

  /// The fused iteration runs on all threads from this many rows (below kMinParallelLength:
  /// it starts one region per solve, not five per iteration). Measured on the 5k-tet FEM
  /// benchmark (3,993 rows, 2 threads, OMP_WAIT_POLICY=passive): 4.1 → 2.7 ms per solve.
  static constexpr int kMinFusedParallelRows = 2048;

  /// Jacobi (or no) preconditioning runs the fused iteration below, "sgs" IterateSgs on its own
  /// copy of the blocks (or, for a matrix not made of node blocks, the fused Jacobi iteration).
  [[nodiscard]] bool fused() const {
    return kind_ == Preconditioner::kJacobi || kind_ == Preconditioner::kNone ||
           kind_ == Preconditioner::kSgs;
  }
  /// The block Gauss-Seidel sweeps run (node_block_sgs.h).
  [[nodiscard]] bool sgs() const { return kind_ == Preconditioner::kSgs && node_blocks_; }

  /// IterateFused's and IterateSgs's partial sums: three per block (or domain) and round parity,
  /// each block's on its own cache line. Two rounds alternate, so a thread that runs ahead never
  /// overwrites sums another is still reading; totals add the blocks in block order.
  struct alignas(64) PartialSums {
    double sum[3] = {0.0, 0.0, 0.0};
  };
  struct RoundSums {
    PartialSums* partials;
    int count;
    [[nodiscard]] double* slot(int round, int block) const {
      return partials[(round & 1) * count + block].sum;
    }
    [[nodiscard]] double total(int round, int which) const {
      double sum = 0.0;
      for (int k = 0; k < count; ++k) sum += slot(round, k)[which];
      return sum;
    }
  };
  RoundSums ResetRoundSums(int count) {
    partials_.assign(static_cast<std::size_t>(2 * count), PartialSums{});
    return {partials_.data(), count};
  }

  /// Runs sweep(team, t) for t < threads in one OpenMP region, or sweep(1, 0) on this thread
  /// without a region when threads is 1 (even an inactive region costs a futex call).
  template <class Sweep>
  static void RunTeam(int threads, const Sweep& sweep) {
    if (threads > 1) {
#pragma omp parallel num_threads(threads)
      sweep(omp_get_num_threads(), omp_get_thread_num());
    } else {
      sweep(1, 0);
    }
  }

  /// The same contract as Iterate, for "sgs": CG with symmetric block Gauss-Seidel in
  /// Eisenstat's form (node_block_sgs.h), which needs no product with A: per iteration a
  /// backward and a forward sweep of each domain and an update, the threads (each with a run of
  /// whole domains) meeting at a TeamBarrier after each (three per iteration; t from other
  /// domains must be final before the forward sweep). The sums are per domain, added in domain
  /// order: the bits do not depend on the thread count. `r_norm` is ‖r_‖ (= ‖b − A x‖).
  ///
  /// The stopping test reads the residual r = (D + L) Z (equal to b − A x in exact arithmetic)
  /// from an update that also sweeps the L blocks, which costs about a quarter of an iteration.
  /// So it runs only where it may decide: when ‖r‖ ≈ q √γ, q from the last computed residual
  /// (‖r₀‖ at the start), is within 4× of the target, and every kSgsCheckEvery rounds to
  /// refresh q. The test is never skipped near convergence by more than q's drift allows.
  static constexpr int kSgsCheckEvery = 8;
  bool IterateSgs(double target, double r_norm, int& iterations, VecX& x, bool on_team) {
    const int domains = sgs_.domains();
    const int threads =
        on_team && rows_ >= kMinFusedParallelRows ? std::min(omp_get_max_threads(), domains) : 1;
    // Per domain: (r, r), (Z, R) = γ, (P, w).
    const RoundSums sums = ResetRoundSums(domains);
    TeamBarrier barrier;
    double* px = x.data();
    const double* pr = r_.data();
    int done = iterations;
    bool ok = false;
    RunTeam(threads, [&](const int team, const int t) {
      const int first = domains * t / team, last = domains * (t + 1) / team;
      auto slot = [&](int round, int d) { return sums.slot(round, d); };
      auto total = [&](int round, int which) { return sums.total(round, which); };
      for (int d = first; d < last; ++d) slot(0, d)[1] = sgs_.Start(pr, d);
      barrier.Wait(team);
      double gamma = total(0, 1), beta = 0.0;
      double q2 = r_norm * r_norm / gamma;  // ‖r‖² / γ at the last computed residual
      int last_check = 0;
      int local = done;
      bool converged = false;
      for (int round = 1; local < options_.max_iterations; ++round) {
        if (!(gamma > 0.0) || !std::isfinite(gamma)) break;  // not SPD, NaN
        for (int d = first; d < last; ++d) sgs_.Backward(beta, d);
        barrier.Wait(team);
        for (int d = first; d < last; ++d) slot(round, d)[2] = sgs_.Forward(d);
        barrier.Wait(team);
        const double alpha = gamma / total(round, 2);
        if (!(alpha > 0.0) || !std::isfinite(alpha)) break;
        // γ is the residual's before this update: the estimate errs towards testing early.
        const bool check =
            q2 * gamma <= 16.0 * target * target || round - last_check >= kSgsCheckEvery;
        for (int d = first; d < last; ++d) {
          const SgsUpdateSums update = sgs_.Update(alpha, px, check, d);
          slot(round, d)[0] = update.rr;
          slot(round, d)[1] = update.zr;
        }
        barrier.Wait(team);
        ++local;
        const double gamma_next = total(round, 1);
        if (check) {
          const double rr = total(round, 0);
          if (!std::isfinite(rr)) break;
          if (std::sqrt(rr) <= target) {
            converged = true;
            break;
          }
          q2 = rr / gamma_next;
          last_check = round;
        }
        beta = gamma_next / gamma;
        gamma = gamma_next;
      }
      if (t == 0) {
        done = local;
        ok = converged;
      }
    });
    iterations = done;
    return ok;
  }

  /// The same contract as Iterate, for the element-wise preconditioners: the Chronopoulos–Gear
  /// form of PCG (Chronopoulos & Gear, "s-step iterative methods for symmetric linear
  /// systems", J. Comput. Appl. Math. 25, 1989), which keeps s = A p by the recurrence
  /// s ← w + β s with w = A z, so that both inner products of an iteration, (r, z) and (w, z),
  /// are taken together. An iteration is then two sweeps over the rows: (1) p ← z + βp,
  /// s ← w + βs, x += αp, r −= αs, z = M⁻¹r with the partial sums of (r, r) and (r, z); (2)
  /// w = A z with the partial sum of (w, z). One OpenMP region covers all iterations, its
  /// threads meeting at a TeamBarrier after each sweep (two per iteration, against five region
  /// starts for Iterate). The rows are split into kSumBlocks contiguous blocks of about equal
  /// work (whole nodes for a node-block matrix), whatever the team; each thread sweeps a run of
  /// whole blocks, and the blocks' partial sums are added in block order, so the bits do not
  /// depend on the thread count. That lets each solve choose its team (Solve's team_choice_):
  /// beside a busy neighbour a two-thread team waits at every barrier for a descheduled
  /// thread, and one thread is faster. In exact arithmetic the iterates are those of Iterate; the
  /// recurred s can drift from A p in floating point, which Solve's true-residual check catches (it
  /// restarts CG from the true residual).
  bool IterateFused(double target, int& iterations, VecX& x, bool on_team) {
    const int n = static_cast<int>(rows_);
    const SparseMatrix& A = *matrix_;
    const bool blocks = block_copy_ready_;
    // Row blocks, split so that every block gets about the same work, counted as nonzeros plus
    // 8 per row (the vector updates' loads and stores).
    const int unit = blocks ? 3 : 1;
    const int units = n / unit;
    const int count = std::max(1, std::min(kSumBlocks, units));
    const int* outer = A.outerIndexPtr();
    block_start_.resize(static_cast<std::size_t>(count) + 1);
    for (int k = 0; k <= count; ++k) {
      if (k == count) {
        block_start_[static_cast<std::size_t>(k)] = n;
        break;
      }
      const std::int64_t goal = (std::int64_t{outer[n]} + 8 * std::int64_t{n}) * k / count;
      int lo = 0, hi = units;  // the first unit whose start reaches the goal
      while (lo < hi) {
        const int mid = lo + (hi - lo) / 2;
        if (outer[unit * mid] + 8 * std::int64_t{unit} * mid < goal)
          lo = mid + 1;
        else
          hi = mid;
      }
      block_start_[static_cast<std::size_t>(k)] = unit * lo;
    }
    // On one thread below kMinFusedParallelRows, or when Solve chose this thread alone: then
    // without an OpenMP region (even an inactive one costs a futex call; EP on a small mesh
    // solves 10,000 times per simulated second).
    const int threads = on_team && n >= kMinFusedParallelRows ? omp_get_max_threads() : 1;
    // Per block: (r, r), (r, z), (w, z).
    const RoundSums sums = ResetRoundSums(count);
    TeamBarrier barrier;
    const double* __restrict inverse = inverse_diagonal_.data();
    const int* start = block_start_.data();
    double* __restrict px = x.data();
    double* __restrict pr = r_.data();
    double* __restrict pz = z_.data();
    double* __restrict pp = p_.data();
    double* __restrict ps = q_.data();
    double* __restrict pw = w_.data();
    int done = iterations;
    bool ok = false;
    RunTeam(threads, [&](const int team, const int t) {
      const int first_block = count * t / team, end_block = count * (t + 1) / team;
      auto slot = [&](int round, int block) { return sums.slot(round, block); };
      auto total = [&](int round, int which) { return sums.total(round, which); };
      auto spmv_and_wz = [&](int round) {  // sweep (2): w = A z, partial (w, z)
        for (int k = first_block; k < end_block; ++k) {
          const int begin = start[k], end = start[k + 1];
          if (blocks)
            block_copy_.MultiplyNodes(pz, pw, begin / 3, end / 3);
          else
            SymmetricSpMVRows(A, pz, pw, begin, end);
          slot(round, k)[2] = DotRows(pw, pz, begin, end);
        }
      };
      // Start: z = M⁻¹ r, then w = A z, (r, z) and (w, z).
      for (int k = first_block; k < end_block; ++k) {
        double rz = 0.0;
        for (int i = start[k]; i < start[k + 1]; ++i) {
          pz[i] = inverse[i] * pr[i];
          rz += pr[i] * pz[i];
          pp[i] = 0.0;  // round 1 takes p = z, s = w (β = 0): no value left from an earlier
          ps[i] = 0.0;  // solve may survive, not even a non-finite one (0 · ∞ is NaN)
        }
        slot(0, k)[1] = rz;
      }
      barrier.Wait(team);
      spmv_and_wz(0);
      barrier.Wait(team);
      double gamma = total(0, 1), delta = total(0, 2);
      double alpha = 0.0, beta = 0.0;
      int local = done;
      bool converged = false;
      for (int round = 1; local < options_.max_iterations; ++round) {
        // Scalars from the sums of the last round: every thread computes the same bits.
        if (round == 1) {
          beta = 0.0;
          alpha = gamma / delta;
        } else {
          const double gamma_next = total(round - 1, 1);
          beta = gamma_next / gamma;
          gamma = gamma_next;
          delta = total(round - 1, 2);
          alpha = gamma / (delta - beta * gamma / alpha);
        }
        if (!(gamma > 0.0) || !(alpha > 0.0) || !std::isfinite(alpha)) break;  // not SPD, NaN
        for (int k = first_block; k < end_block; ++k) {
          const CgUpdateSums sums =
              CgUpdateRows(alpha, beta, inverse, pw, px, pr, pz, pp, ps, start[k], start[k + 1]);
          slot(round, k)[0] = sums.rr;
          slot(round, k)[1] = sums.rz;
        }
        barrier.Wait(team);
        ++local;
        const double rr_total = total(round, 0);
        if (!std::isfinite(rr_total)) break;
        if (std::sqrt(rr_total) <= target) {
          converged = true;
          break;
        }
        if (local >= options_.max_iterations) break;  // every thread agrees: no product wasted
        spmv_and_wz(round);
        barrier.Wait(team);
      }
      if (t == 0) {
        done = local;
        ok = converged;
      }
    });
    iterations = done;
    return ok;
  }

  /// CG from the current r_ (= b − A x) until the recursive residual norm is ≤ target (returns
  /// true), or the iteration budget is spent, or a breakdown or non-finite value (false).
  bool Iterate(double target, int& iterations, VecX& x) {
    double rz = Precondition();
    if (!(rz > 0.0) || !std::isfinite(rz)) return false;
    p_ = z_;
    while (iterations < options_.max_iterations) {
      Multiply(p_, q_);
      const double pq = ParallelDot(p_, q_, scratch_);
      if (!(pq > 0.0) || !std::isfinite(pq)) return false;  // A not SPD, or NaN
      const double alpha = rz / pq;
      double* __restrict px = x.data();
      double* __restrict pr = r_.data();
      const double* __restrict pp = p_.data();
      const double* __restrict pqv = q_.data();
      const double rr = DeterministicParallelSum(rows_, scratch_, [=](Index begin, Index end) {
        double s = 0.0;
        for (Index i = begin; i < end; ++i) {
          px[i] += alpha * pp[i];
          pr[i] -= alpha * pqv[i];
          s += pr[i] * pr[i];
        }
        return s;
      });
      ++iterations;
      if (!std::isfinite(rr)) return false;
      if (std::sqrt(rr) <= target) return true;
      const double rz_next = Precondition();
      if (!(rz_next > 0.0) || !std::isfinite(rz_next)) return false;
      ParallelXpby(z_, rz_next / rz, p_);
      rz = rz_next;
    }
    return false;
  }

  LinearSolverOptions options_;
  Preconditioner kind_;
  Index rows_ = 0;
  Index nonzeros_ = 0;
  bool analysed_ = false;
  bool node_blocks_ = false;              ///< the analysed pattern has HasNodeBlockPattern
  NodeBlockCopy block_copy_;              ///< block-row copy of A for the fused CG
  NodeBlockSgs sgs_;                      ///< "sgs": the sweeps on block_copy_
  bool block_copy_ready_ = false;         ///< block_copy_ holds the values of matrix_
  const SparseMatrix* matrix_ = nullptr;  ///< the last successfully factorised A
  bool refactorized_ = false;
  bool has_factor_ = false;         ///< cholesky_ / amg_ holds a valid factorisation / hierarchy
  bool refactor_pending_ = false;   ///< the last Solve found the lagged factor too weak
  int baseline_iterations_ = 0;     ///< CG iterations of the first Solve after an AMG set-up
  double factor_cost_ = 1.0;        ///< a CHOLMOD factorisation in CG iterations (AnalyzePattern)
  std::int64_t lagged_solves_ = 0;  ///< Solves since the last CHOLMOD factorisation
  std::int64_t lagged_iterations_ = 0;  ///< their CG iterations
  VecX r_, z_, p_, q_;                  ///< residual, preconditioned residual, direction, A p
  VecX w_;                              ///< A z (IterateFused)
  std::vector<PartialSums> partials_;   ///< RoundSums' storage
  std::vector<int> block_start_;  ///< IterateFused's row blocks (kSumBlocks + 1 starts, at most)
  AdaptiveParallel team_choice_;  ///< a fused solve on the team or on the calling thread
  VecX inverse_diagonal_;
  std::vector<int> diagonal_index_;  ///< value index of each diagonal entry (−1: none)
  ReductionScratch scratch_;
  Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>> incomplete_;
  Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> cholesky_;
  SmoothedAggregationAmg amg_;
};

}  // namespace

std::unique_ptr<LinearSolver> MakePcgSolver(const LinearSolverOptions& options) {
  return std::make_unique<PcgSolver>(options);
}

}  // namespace gipsi
