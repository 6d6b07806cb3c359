// NewtonSolver on small algebraic systems: the globalisation (residual and natural
// monotonicity tests), the tolerance semantics, the budget extension of a converging solve, the
// stop request, and the Anderson acceleration of a kept factorisation.

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <vector>

#include "gipsi/base/state.h"
#include "gipsi/numerics/newton.h"
#include "gipsi/numerics/sparse/linear_solver.h"

namespace gipsi {
namespace {

/// A system with a diagonal Jacobian: r_i = f_i(x_i), J_ii = f_i'(x_i). Counts evaluations.
class DiagonalSystem final : public NonlinearSystem {
 public:
  using Fn = std::function<double(int, double)>;
  DiagonalSystem(Fn f, Fn df) : f_(std::move(f)), df_(std::move(df)) {}
  bool CalcResidual(const VecX& d, VecX& r) override {
    ++residuals;
    if (on_evaluation) on_evaluation();
    for (Index i = 0; i < d.size(); ++i) r[i] = f_(static_cast<int>(i), d[i]);
    return r.allFinite();
  }
  bool CalcResidualAndJacobian(const VecX& d, VecX& r, SparseMatrix& J) override {
    ++jacobians;
    if (!CalcResidual(d, r)) return false;
    for (Index i = 0; i < d.size(); ++i) J.coeffRef(i, i) = df_(static_cast<int>(i), d[i]);
    return true;
  }
  int residuals = 0, jacobians = 0;
  std::function<void()> on_evaluation;

 private:
  Fn f_, df_;
};

SparseMatrix DiagonalPattern(Index n) {
  SparseMatrix J(n, n);
  for (Index i = 0; i < n; ++i) J.insert(i, i) = 1;
  J.makeCompressed();
  return J;
}

NewtonStats Solve(DiagonalSystem& system, VecX& x, NewtonOptions options, StopToken stop = {}) {
  NewtonSolver newton(options, MakeLinearSolver(LinearSolverOptions{.type = "ldlt"}));
  SparseMatrix J = DiagonalPattern(x.size());
  newton.Prepare(J);
  return newton.Solve(system, x, J, stop);
}

// A soft unknown u with a mildly nonlinear residual and a stiff unknown v (stiffness K = 1e3
// on a length scale ε = 1e-3) whose first Newton step overshoots: the full step raises ‖r‖
// 1.55× (the stiff residual grows sixfold) while the correction it leaves, Δ̄ = −J₀⁻¹ r(x₁),
// is 7× smaller than Δ — the situation of a nearly incompressible solid, where the residual of
// the stiff volumetric modes jumps while the displacements are already converging.
constexpr double kK = 1e3, kEps = 1e-3;
DiagonalSystem SoftAndStiff() {
  return DiagonalSystem(
      [](int i, double x) {
        return i == 0 ? (x - 1) + 0.1 * (x - 1) * (x - 1) : kK * (x + x * x / kEps);
      },
      [](int i, double x) { return i == 0 ? 1 + 0.2 * (x - 1) : kK * (1 + 2 * x / kEps); });
}

TEST(Newton, AcceptsAFullStepThatRaisesTheResidualButContractsTheIncrement) {
  DiagonalSystem system = SoftAndStiff();
  VecX x(2);
  x << 0, -0.4 * kEps;
  NewtonOptions options;
  options.tolerance = 1e-12;
  const NewtonStats stats = Solve(system, x, options);
  ASSERT_TRUE(stats.converged) << Describe(stats, options);
  EXPECT_GT(stats.residual_history[1], 1.5 * stats.residual_history[0]);  // the residual rose
  EXPECT_EQ(stats.monotonicity_accepts, 1);
  EXPECT_EQ(stats.backtracks, 0);  // every step was a full Newton step
  EXPECT_NEAR(x[0], 1, 1e-12);
  EXPECT_NEAR(x[1], 0, 1e-12 * kEps);

  // A residual-only line search cuts that first step instead.
  DiagonalSystem residual_only = SoftAndStiff();
  VecX y(2);
  y << 0, -0.4 * kEps;
  options.monotonicity_test = false;
  const NewtonStats cut = Solve(residual_only, y, options);
  ASSERT_TRUE(cut.converged);
  EXPECT_GT(cut.backtracks, 0);
  EXPECT_EQ(cut.monotonicity_accepts, 0);
}

TEST(Newton, BacktrackingStillRescuesAnOvershootingStep) {
  // r = arctan(x) from x₀ = 3: the full Newton step lands at −9.5, where both |r| and the
  // simplified correction grow, and plain Newton diverges; the line search halves twice.
  auto atan_system = [] {
    return DiagonalSystem([](int, double x) { return std::atan(x); },
                          [](int, double x) { return 1 / (1 + x * x); });
  };
  DiagonalSystem system = atan_system();
  VecX x = VecX::Constant(1, 3.0);
  NewtonOptions options;
  options.tolerance = 1e-12;
  const NewtonStats stats = Solve(system, x, options);
  ASSERT_TRUE(stats.converged) << Describe(stats, options);
  EXPECT_GE(stats.backtracks, 2);
  EXPECT_EQ(stats.monotonicity_accepts, 0);
  EXPECT_NEAR(x[0], 0, 1e-12);

  DiagonalSystem plain = atan_system();
  VecX y = VecX::Constant(1, 3.0);
  options.line_search = false;
  EXPECT_FALSE(Solve(plain, y, options).converged);
}

// r = x³ from x₀: Newton contracts x by 2/3 and the residual by (2/3)³ ≈ 0.296 per iteration
// (a triple root), so the iteration counts of the tolerances are known in closed form.
DiagonalSystem Cubic() {
  return DiagonalSystem([](int, double x) { return x * x * x; },
                        [](int, double x) { return 3 * x * x; });
}

TEST(Newton, RelativeResidualToleranceIsRelativeToTheInitialResidual) {
  // ‖r_k‖ = (8/27)^k ‖r_0‖ ≤ 1e-3 ‖r_0‖ first at k = ⌈ln 1e-3 / ln(8/27)⌉ = 6, whatever x₀.
  for (double x0 : {1.0, 100.0}) {
    DiagonalSystem system = Cubic();
    VecX x = VecX::Constant(1, x0);
    NewtonOptions options;
    options.tolerance = 1e-3;
    const NewtonStats stats = Solve(system, x, options);
    ASSERT_TRUE(stats.converged);
    EXPECT_EQ(stats.iterations, 6) << "x0 = " << x0;
  }
}

TEST(Newton, AbsoluteResidualToleranceIsInTheResidualsUnits) {
  // From x₀ = 10 (r₀ = 1000) with a relative tolerance too tight to matter: ‖r_k‖ ≤ 1e-3
  // first at k = ⌈ln 1e-6 / ln(8/27)⌉ = 12; from x₀ = 1 (r₀ = 1): k = ⌈ln 1e-3 / ln(8/27)⌉ = 6.
  for (auto [x0, expected] : {std::pair{10.0, 12}, std::pair{1.0, 6}}) {
    DiagonalSystem system = Cubic();
    VecX x = VecX::Constant(1, x0);
    NewtonOptions options;
    options.tolerance = 1e-30;
    options.absolute_tolerance = 1e-3;
    options.max_iterations = 50;
    const NewtonStats stats = Solve(system, x, options);
    ASSERT_TRUE(stats.converged);
    EXPECT_EQ(stats.iterations, expected) << "x0 = " << x0;
  }
}

TEST(Newton, IncrementTolerancesMeasureTheFullCorrection) {
  // Iteration k's correction is Δ = −x_{k−1}/3 = −(2/3)^{k−1}/3 from x₀ = 1.
  // Absolute: ≤ 1e-2 first at k − 1 = ⌈ln 0.03 / ln(2/3)⌉ = 9, k = 10.
  DiagonalSystem system = Cubic();
  VecX x = VecX::Constant(1, 1.0);
  NewtonOptions options;
  options.tolerance = 1e-300;
  options.increment_tolerance = 1e-2;
  options.max_iterations = 50;
  NewtonStats stats = Solve(system, x, options);
  ASSERT_TRUE(stats.converged);
  EXPECT_EQ(stats.iterations, 10);
  // Relative to the iterate, |Δ| = |x_k|/2 (x_k = (2/3) x_{k−1}): never below 0.4, always
  // below 0.6.
  options.increment_tolerance = 0;
  options.relative_increment_tolerance = 0.4;
  x.setConstant(1.0);
  DiagonalSystem again = Cubic();
  stats = Solve(again, x, options);
  EXPECT_FALSE(stats.converged);
  options.relative_increment_tolerance = 0.6;
  x.setConstant(1.0);
  DiagonalSystem once = Cubic();
  stats = Solve(once, x, options);
  ASSERT_TRUE(stats.converged);
  EXPECT_EQ(stats.iterations, 1);
}

TEST(Newton, AConvergingSolveIsNotCutShort) {
  // The cubic needs ⌈ln 1e-8 / ln(8/27)⌉ = 16 iterations at tolerance 1e-8. With a budget of 10
  // it is still contracting by 0.3 per iteration when the budget runs out: Newton goes on (up
  // to 2 × 10) instead of failing, which would make FemSolid bisect a converging increment.
  DiagonalSystem system = Cubic();
  VecX x = VecX::Constant(1, 1.0);
  NewtonOptions options;
  options.max_iterations = 10;
  NewtonStats stats = Solve(system, x, options);
  ASSERT_TRUE(stats.converged) << Describe(stats, options);
  EXPECT_EQ(stats.iterations, 16);
  // The extension is bounded: 1e-16 needs 31 iterations, more than 2 × 10.
  DiagonalSystem tight = Cubic();
  x.setConstant(1.0);
  options.tolerance = 1e-16;
  options.relative_increment_tolerance = 0;
  stats = Solve(tight, x, options);
  EXPECT_FALSE(stats.converged);
  EXPECT_EQ(stats.iterations, 20);
}

TEST(Newton, AStopRequestEndsTheSolveWithinTheIteration) {
  // The flag is raised inside the 4th residual evaluation; the solve returns without another
  // linear solve: at most the Jacobian of the step just accepted is assembled after it.
  DiagonalSystem system = Cubic();
  std::atomic<bool> flag{false};
  int at_request = -1;
  system.on_evaluation = [&] {
    if (system.residuals == 4) {
      flag.store(true);
      at_request = system.residuals;
    }
  };
  VecX x = VecX::Constant(1, 1.0);
  NewtonOptions options;
  options.tolerance = 1e-12;
  const NewtonStats stats = Solve(system, x, options, StopToken(&flag));
  EXPECT_TRUE(stats.interrupted);
  EXPECT_FALSE(stats.converged);
  // Evaluations: r₀ and J₀; iteration 1: trial, J₁; iteration 2: the trial raising the flag,
  // then J₂ of the accepted step; no iteration 3.
  EXPECT_EQ(system.residuals - at_request, 1);
  EXPECT_EQ(stats.iterations, 2);
  EXPECT_EQ(Describe(stats, options).rfind("Newton: stopped on request after ", 0), 0u);
}

TEST(Newton, AnIndefiniteTangentFallsBackToLdltAndOtherwiseSaysWhatToTry) {
  // r = x − x³/3 − 0.5 from x₀ = 1.5: J = 1 − x² = −1.25 < 0. "ldlt" refuses it as SPD,
  // switches to its indefinite mode and converges to the root x ≈ 1.384 (J < 0 there too)...
  auto system_of = [] {
    return DiagonalSystem([](int, double x) { return x - x * x * x / 3 - 0.5; },
                          [](int, double x) { return 1 - x * x; });
  };
  DiagonalSystem system = system_of();
  VecX x = VecX::Constant(1, 1.5);
  NewtonOptions options;
  options.tolerance = 1e-12;
  const NewtonStats stats = Solve(system, x, options);
  ASSERT_TRUE(stats.converged) << Describe(stats, options);
  EXPECT_NEAR(x[0], 1.3844, 1e-3);
  EXPECT_TRUE(stats.switched_to_indefinite);  // the object logs it once
  // ... while CG, for SPD matrices only, fails and the message says why and what to try.
  DiagonalSystem cg_system = system_of();
  NewtonSolver cg(options, MakeLinearSolver(LinearSolverOptions{.type = "cg"}));
  SparseMatrix J = DiagonalPattern(1);
  cg.Prepare(J);
  VecX y = VecX::Constant(1, 1.5);
  const NewtonStats failed = cg.Solve(cg_system, y, J);
  ASSERT_TRUE(failed.linear_failure);
  EXPECT_EQ(failed.linear_failure_kind, LinearFailure::kNotPositiveDefinite);
  EXPECT_EQ(Describe(failed, options, cg.linear_solver().name()),
            "Newton: the tangent matrix is not positive definite at iteration 1: the 'cg+sgs' "
            "linear solver needs a positive definite matrix and could not factorise it. A tangent "
            "turns indefinite when a load increment is too large for the volumetric penalty "
            "(bulk_modulus) or a follower pressure, or past a buckling or limit point: try more "
            "\"load_steps\", or a solver that accepts indefinite matrices, \"linear_solver\": "
            "{\"type\": \"ldlt\"} or {\"type\": \"cholmod\"}; |r|: 1.25e-01");
}

// A box of sides 1 + u_i (volume V = Π(1 + u_i)) held by springs k, squeezed along x by a
// force a and filled with a nearly incompressible fluid: V_b(p) = V₀ − C p with C = 1e-9
// (w = 1/C = 1e9, the blood's stiffness when the heart's valves are closed). The pressure p is
// either a bordered unknown (residual r_p = V(u) − V_b(p)) or, `condensed`, solved from r_p = 0
// inside the residual, p(u) = (V₀ − V(u))/C, which makes the coupling a penalty of weight w.
class FluidFilledBox final : public NonlinearSystem {
 public:
  explicit FluidFilledBox(bool condensed) : condensed_(condensed) {}
  static constexpr double kSpring = 10, kSqueeze = 2, kCompliance = 1e-9;
  bool CalcResidual(const VecX& x, VecX& r) override {
    ++residuals;
    const Vec3 side = Vec3::Ones() + x.head<3>();
    volume_ = side.prod();
    gradient_ = Vec3(side.y() * side.z(), side.x() * side.z(), side.x() * side.y());
    pressure_ = condensed_ ? (1.0 - volume_) / kCompliance : x[3];
    const Vec3 ru = kSpring * x.head<3>() - pressure_ * gradient_ + Vec3(kSqueeze, 0, 0);
    r.head<3>() = ru;
    if (!condensed_) r[3] = volume_ - (1.0 - kCompliance * pressure_);
    b_ = gradient_;
    return r.allFinite();
  }
  bool CalcResidualAndJacobian(const VecX& x, VecX& r, SparseMatrix& J) override {
    if (!CalcResidual(x, r)) return false;
    const Vec3 side = Vec3::Ones() + x.head<3>();
    // k I − p ∂²V/∂u² (the follower part; ∂²V/∂u_i∂u_j = the third side for i ≠ j).
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        J.coeffRef(i, j) = i == j ? kSpring : -pressure_ * side[3 - i - j];
    return true;
  }
  [[nodiscard]] int num_low_rank_terms() const override { return 1; }
  void LowRankTerm(int /*k*/, const VecX*& b, double& w) const override {
    b = &b_;
    w = 1 / kCompliance;
  }
  [[nodiscard]] int num_bordered() const override { return condensed_ ? 0 : 1; }
  [[nodiscard]] double pressure() const { return pressure_; }
  [[nodiscard]] double volume() const { return volume_; }
  int residuals = 0;

 private:
  bool condensed_;
  double volume_ = 1, pressure_ = 0;
  Vec3 gradient_ = Vec3::Ones();
  VecX b_ = VecX::Ones(3);
};

SparseMatrix DensePattern(Index n) {
  SparseMatrix J(n, n);
  for (Index j = 0; j < n; ++j)
    for (Index i = 0; i < n; ++i) J.insert(i, j) = i == j ? 1 : 0;
  J.makeCompressed();
  return J;
}

NewtonStats SolveBox(FluidFilledBox& box, VecX& x, bool reuse) {
  NewtonOptions options;
  options.tolerance = 1e-10;
  options.reuse_factorization = reuse;
  NewtonSolver newton(options, MakeLinearSolver(LinearSolverOptions{.type = "ldlt"}));
  SparseMatrix J = DensePattern(3);
  newton.Prepare(J, box.num_bordered());
  return newton.Solve(box, x, J);
}

TEST(Newton, ABorderedPressureKeepsQuadraticConvergenceUnderAStiffVolumeConstraint) {
  // Bordered: Newton on (u, p) converges quadratically from rest (5 iterations measured, no
  // step cut) to a state that satisfies both equations: r_u to the tolerance and the volume to
  // C times the pressure error it allows.
  FluidFilledBox bordered(false);
  VecX x = VecX::Zero(4);
  const NewtonStats stats = SolveBox(bordered, x, false);
  ASSERT_TRUE(stats.converged);
  EXPECT_LE(stats.iterations, 6);
  EXPECT_EQ(stats.backtracks, 0);
  // The volume is held (the fluid compresses by C p, about 1e-9).
  EXPECT_NEAR(bordered.volume(), 1.0 - FluidFilledBox::kCompliance * x[3], 1e-12);
  EXPECT_GT(x[3], 0.5);  // the squeeze is carried by the pressure (about 2/3 of it)
  // Condensed, the same problem (the penalty formulation the heart used until stop 38) cuts
  // its steps and needs more iterations (13 and 44 step halvings measured); where it
  // converges, it converges to the same state.
  FluidFilledBox condensed(true);
  VecX y = VecX::Zero(3);
  const NewtonStats penalty = SolveBox(condensed, y, false);
  EXPECT_GT(penalty.iterations + penalty.backtracks, stats.iterations + stats.backtracks);
  if (penalty.converged) {
    EXPECT_LT((y - x.head<3>()).lpNorm<Eigen::Infinity>(), 1e-8);
  }
  // Modified Newton (a kept factorisation and the b it was made with; 9 iterations and 3
  // factorisations measured) converges to the same state too.
  FluidFilledBox kept(false);
  VecX z = VecX::Zero(4);
  const NewtonStats modified = SolveBox(kept, z, true);
  ASSERT_TRUE(modified.converged);
  EXPECT_LT((z - x).head<3>().lpNorm<Eigen::Infinity>(), 1e-9);
  EXPECT_NEAR(z[3], x[3], 1e-6 * x[3]);
}

// A chain of n nonlinear springs between two walls, each node pulled by the same load:
// r_i = k (2 x_i − x_{i−1} − x_{i+1}) + c x_i³ − load. Raising the load step by step makes it
// the modified Newton of a time-stepping object: the factorisation of an earlier tangent is
// kept across steps while it still halves the residual, and the cubic term makes that tangent
// stiffer than the kept one as the chain stretches.
class SpringChain final : public NonlinearSystem {
 public:
  static constexpr double kSpring = 1, kCubic = 0.05;
  double load = 0;
  bool CalcResidual(const VecX& x, VecX& r) override {
    const Index n = x.size();
    for (Index i = 0; i < n; ++i) {
      const double left = i > 0 ? x[i - 1] : 0, right = i + 1 < n ? x[i + 1] : 0;
      r[i] = kSpring * (2 * x[i] - left - right) + kCubic * x[i] * x[i] * x[i] - load;
    }
    return r.allFinite();
  }
  bool CalcResidualAndJacobian(const VecX& x, VecX& r, SparseMatrix& J) override {
    if (!CalcResidual(x, r)) return false;
    for (Index i = 0; i < x.size(); ++i) {
      J.coeffRef(i, i) = 2 * kSpring + 3 * kCubic * x[i] * x[i];
      if (i > 0) J.coeffRef(i, i - 1) = J.coeffRef(i - 1, i) = -kSpring;
    }
    return true;
  }
  [[nodiscard]] double force_scale() const override { return std::abs(load); }
};

SparseMatrix ChainPattern(Index n) {
  SparseMatrix J(n, n);
  for (Index i = 0; i < n; ++i)
    for (Index j = std::max<Index>(i - 1, 0); j <= std::min<Index>(i + 1, n - 1); ++j)
      J.insert(i, j) = i == j ? 1 : 0;
  J.makeCompressed();
  return J;
}

constexpr int kChainNodes = 20, kLoadSteps = 24;
double ChainLoad(int step) { return 0.004 * step; }

NewtonOptions KeptFactorOptions(int anderson) {
  NewtonOptions options;
  options.tolerance = 1e-10;
  options.reuse_factorization = true;
  options.anderson = anderson;
  return options;
}

struct ChainRun {
  std::vector<VecX> states;  // after each load step
  int iterations = 0, factorizations = 0, accepts = 0, rejects = 0;
};

// Load steps [first, last] on `newton` (prepared), from x.
void RunChain(NewtonSolver& newton, SparseMatrix& J, VecX& x, int first, int last, ChainRun& run) {
  SpringChain chain;
  for (int step = first; step <= last; ++step) {
    chain.load = ChainLoad(step);
    const NewtonStats stats = newton.Solve(chain, x, J);
    ASSERT_TRUE(stats.converged) << "step " << step << ": " << Describe(stats, newton.options());
    run.iterations += stats.iterations;
    run.factorizations += stats.refactorizations;
    run.accepts += stats.anderson_accepts;
    run.rejects += stats.anderson_rejects;
    run.states.push_back(x);
  }
}

ChainRun SolveChain(int anderson) {
  NewtonSolver newton(KeptFactorOptions(anderson),
                      MakeLinearSolver(LinearSolverOptions{.type = "ldlt"}));
  SparseMatrix J = ChainPattern(kChainNodes);
  newton.Prepare(J);
  VecX x = VecX::Zero(kChainNodes);
  ChainRun run;
  RunChain(newton, J, x, 1, kLoadSteps, run);
  return run;
}

TEST(Newton, AndersonAccelerationOfAKeptFactorisationSavesIterationsAndFindsTheSameStates) {
  const ChainRun plain = SolveChain(0);
  const ChainRun accelerated = SolveChain(5);
  ASSERT_EQ(plain.states.size(), accelerated.states.size());
  // Both end each step at ‖r‖ ≤ 1e-10 max(‖r₀‖, load), and the chain's tangent has
  // ‖J⁻¹‖ ≤ (n + 1)²/π² ≈ 45: each state is within 5e-9 max(‖r₀‖, load) of the solution, far
  // below 2e-8 of the state (about 50 load for the linear chain).
  for (std::size_t s = 0; s < plain.states.size(); ++s) {
    const double scale = plain.states[s].lpNorm<Eigen::Infinity>();
    EXPECT_LT((accelerated.states[s] - plain.states[s]).lpNorm<Eigen::Infinity>(), 2e-8 * scale)
        << "load step " << s + 1;
  }
  // Measured: plain modified Newton 353 iterations and 5 factorisations; accelerated 207 and 3,
  // with 203 accelerated steps accepted and 1 refused.
  EXPECT_EQ(plain.accepts + plain.rejects, 0);
  EXPECT_GT(accelerated.accepts, 0);
  EXPECT_LE(accelerated.iterations, 0.75 * plain.iterations)
      << plain.iterations << " plain iterations";
  EXPECT_LE(accelerated.factorizations, plain.factorizations);
}

TEST(Newton, AResumedSolverContinuesItsAndersonHistoryBitwise) {
  // Twelve load steps, a checkpoint, twelve more: in the same solver, and in a new one
  // restored from the checkpoint. The kept factorisation and the Anderson history it carries
  // both come back, so the iterates are the same bits.
  auto make = [] {
    return NewtonSolver(KeptFactorOptions(5),
                        MakeLinearSolver(LinearSolverOptions{.type = "ldlt"}));
  };
  NewtonSolver first = make();
  SparseMatrix J = ChainPattern(kChainNodes);
  first.Prepare(J);
  VecX x = VecX::Zero(kChainNodes);
  ChainRun before;
  RunChain(first, J, x, 1, kLoadSteps / 2, before);
  StateWriter out;
  first.SaveState(out, J);
  const VecX saved = x;
  ChainRun uninterrupted;
  RunChain(first, J, x, kLoadSteps / 2 + 1, kLoadSteps, uninterrupted);
  ASSERT_GT(uninterrupted.accepts, 0);

  NewtonSolver second = make();
  SparseMatrix J2 = ChainPattern(kChainNodes);
  second.Prepare(J2);
  StateReader in(out.TakeBytes(), "the test's checkpoint");
  second.RestoreState(in, J2);
  VecX y = saved;
  ChainRun resumed;
  RunChain(second, J2, y, kLoadSteps / 2 + 1, kLoadSteps, resumed);
  EXPECT_EQ(resumed.iterations, uninterrupted.iterations);
  EXPECT_EQ(resumed.accepts, uninterrupted.accepts);
  ASSERT_EQ(resumed.states.size(), uninterrupted.states.size());
  for (std::size_t s = 0; s < resumed.states.size(); ++s)
    EXPECT_EQ(resumed.states[s], uninterrupted.states[s]) << "load step " << s;
}

}  // namespace
}  // namespace gipsi
