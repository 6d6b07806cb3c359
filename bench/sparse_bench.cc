// Memory bandwidth of SymmetricSpMV against a STREAM triad on the same OpenMP threads, and the
// cost of the sparse solvers on a stiffness-shaped matrix (26³-node spring lattice, 3 DOFs per
// node, 27-point node stencil: 52,728 rows, 3.95 M nonzeros).
//
// Run: ./build/release/bench/sparse_bench --benchmark_repetitions=5
//      --benchmark_report_aggregates_only=true
//
// Byte counts (the same convention for the triad and the SpMV): every array element read or
// written is counted once, write-allocate traffic is NOT counted. Triad: 3 × 8 B per element.
// SpMV: 12 B per nonzero (8 B value + 4 B row index), 4 B per column pointer, 8 B per entry of
// x (read once, assuming the gathered x stays in cache) and 8 B per entry of y.
// All benchmarks use real (wall-clock) time, since the work runs on several threads.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <utility>

#include <benchmark/benchmark.h>
#include <omp.h>

#include "gipsi/numerics/sparse/linear_solver.h"
#include "gipsi/numerics/sparse/model_problems.h"
#include "stream_triad.h"

namespace gipsi {
namespace {

/// The benchmark lattice: n³ nodes, springs 20× stiffer in the upper half (a stiff inclusion),
/// springs scaled by `scale`, plus a small mass shift. Cached: building the large one takes a
/// second, and Google Benchmark calls each function once per repetition.
const SparseMatrix& Lattice(int n, double scale = 1.0) {
  static std::map<std::pair<int, double>, SparseMatrix> cache;
  auto [it, inserted] = cache.try_emplace({n, scale});
  if (inserted) {
    it->second = MakeSpringLattice3D(
        n, 1e-2, [scale](const Vec3& p) { return scale * (p.z() > 0.5 ? 20.0 : 1.0); });
  }
  return it->second;
}

VecX Ones(Index n) { return VecX::Ones(n); }

/// A right-hand side b = A x_true with x_true uniform in (−1, 1) from a fixed seed. (Not b = 1:
/// a constant vector is a rigid translation, an eigenvector of the lattice matrices, which CG
/// solves in one iteration whatever the preconditioner.)
VecX ManufacturedRhs(const SparseMatrix& A) {
  std::mt19937 engine(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  VecX x_true(A.cols());
  for (Index i = 0; i < x_true.size(); ++i) x_true[i] = uniform(engine);
  VecX b(A.rows());
  SymmetricSpMV(A, x_true, b);
  return b;
}

void SetThreadCounter(benchmark::State& state) {
  state.counters["threads"] = static_cast<double>(omp_get_max_threads());
}

// The STREAM triad (stream_triad.h).
void BM_StreamTriad(benchmark::State& state) { RunStreamTriad(state); }
BENCHMARK(BM_StreamTriad)->UseRealTime()->Unit(benchmark::kMillisecond);

// y = A x on the lattice with n³ nodes: 26 → 52,728 rows and 3.95 M nonzeros (47 MB of values
// and indices); 40 → 192,000 rows and 14.8 M nonzeros (178 MB).
void BM_SymmetricSpMV(benchmark::State& state) {
  const SparseMatrix& A = Lattice(static_cast<int>(state.range(0)));
  const VecX x = Ones(A.cols());
  VecX y(A.rows());
  for (auto _ : state) {
    SymmetricSpMV(A, x, y);
    benchmark::DoNotOptimize(y.data());
    benchmark::ClobberMemory();
  }
  const std::int64_t bytes = 12 * A.nonZeros() + 4 * (A.cols() + 1) + 8 * A.cols() + 8 * A.rows();
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * bytes);
  state.counters["rows"] = static_cast<double>(A.rows());
  state.counters["nnz"] = static_cast<double>(A.nonZeros());
  SetThreadCounter(state);
}
BENCHMARK(BM_SymmetricSpMV)->Arg(26)->Arg(40)->UseRealTime()->Unit(benchmark::kMicrosecond);

/// Solver settings of the solver benchmarks (defaults otherwise: tolerance 1e-6).
LinearSolverOptions Options(const std::string& type, const std::string& preconditioner) {
  LinearSolverOptions options;
  options.type = type;
  options.preconditioner = preconditioner;
  return options;
}

/// One time step's linear algebra on the 26³ lattice: Factorize(A) + Solve from x = 0. Counters:
/// CG iterations, fraction of steps that refactorised, and the Factorize share of the time.
/// For "cholesky" the preconditioner is a factorisation of the matrix with 5 % softer springs,
/// made before the timed loop (the lagged regime it is meant for: Factorize only records A);
/// likewise for "amg", whose Factorize then only refreshes the finest level.
void RunSolverStep(benchmark::State& state, const std::string& type,
                   const std::string& preconditioner) {
  const SparseMatrix& A = Lattice(26);
  const VecX b = ManufacturedRhs(A);
  auto solver = MakeLinearSolver(Options(type, preconditioner));
  if (preconditioner == "amg") {  // the lattice's rigid-body modes (node = x + n (y + n z))
    constexpr int n = 26;
    VecX positions(3 * n * n * n);
    for (int node = 0; node < n * n * n; ++node)
      positions.segment<3>(3 * node) = Vec3(node % n, (node / n) % n, node / (n * n)) / (n - 1);
    solver->SetNearNullSpace(RigidBodyModes(positions));
  }
  solver->AnalyzePattern(A);
  const bool lagged = preconditioner == "cholesky" || preconditioner == "amg";
  if (lagged && type == "cg" && !solver->Factorize(Lattice(26, 1 / 1.05))) {
    state.SkipWithError("factorisation failed");
    return;
  }
  VecX x(A.rows());
  double iterations = 0;
  double refactorizations = 0;
  double factorize_seconds = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const bool factorized = solver->Factorize(A);
    factorize_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!factorized) {
      state.SkipWithError("factorisation failed");
      return;
    }
    x.setZero();
    const LinearSolveStats stats = solver->Solve(b, x);
    if (!stats.converged) {
      state.SkipWithError("not converged");
      return;
    }
    iterations += stats.iterations;
    refactorizations += stats.refactorized ? 1 : 0;
  }
  const double steps = static_cast<double>(state.iterations());
  state.counters["cg_iterations"] = iterations / steps;
  state.counters["refactorized"] = refactorizations / steps;
  state.counters["factorize_ms"] = 1e3 * factorize_seconds / steps;
  SetThreadCounter(state);
}

void BM_SolveStep_CgJacobi(benchmark::State& state) { RunSolverStep(state, "cg", "jacobi"); }
void BM_SolveStep_CgIc(benchmark::State& state) { RunSolverStep(state, "cg", "ic"); }
void BM_SolveStep_CgLaggedCholesky(benchmark::State& state) {
  RunSolverStep(state, "cg", "cholesky");
}
void BM_SolveStep_CgLaggedAmg(benchmark::State& state) { RunSolverStep(state, "cg", "amg"); }
void BM_SolveStep_Cholmod(benchmark::State& state) { RunSolverStep(state, "cholmod", "none"); }
void BM_SolveStep_Ldlt(benchmark::State& state) { RunSolverStep(state, "ldlt", "none"); }
BENCHMARK(BM_SolveStep_CgJacobi)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SolveStep_CgIc)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SolveStep_CgLaggedCholesky)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SolveStep_CgLaggedAmg)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SolveStep_Cholmod)->UseRealTime()->Unit(benchmark::kMillisecond);
// Eigen's simplicial LDLᵀ needs about two minutes per factorisation of this matrix (no
// supernodes, no BLAS), so it runs once, not once per repetition.
BENCHMARK(BM_SolveStep_Ldlt)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(1);

/// The symbolic analysis alone (ordering + elimination tree), paid once per mesh.
void RunAnalyze(benchmark::State& state, const std::string& type) {
  const SparseMatrix& A = Lattice(26);
  auto solver = MakeLinearSolver(Options(type, "none"));
  for (auto _ : state) solver->AnalyzePattern(A);
}
void BM_AnalyzePattern_Cholmod(benchmark::State& state) { RunAnalyze(state, "cholmod"); }
void BM_AnalyzePattern_Ldlt(benchmark::State& state) { RunAnalyze(state, "ldlt"); }
BENCHMARK(BM_AnalyzePattern_Cholmod)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_AnalyzePattern_Ldlt)->UseRealTime()->Unit(benchmark::kMillisecond);

/// A Solve alone with an existing factorisation: the price of one application of the lagged
/// Cholesky preconditioner, or of one modified-Newton iteration's back-substitution (plus one
/// SpMV for the residual check). On the n³ lattice: 14³ (8,232 rows, like the fine heart's
/// tangent) and 26³.
void BM_DirectSolveOnly_Cholmod(benchmark::State& state) {
  const SparseMatrix& A = Lattice(static_cast<int>(state.range(0)));
  const VecX b = ManufacturedRhs(A);
  auto solver = MakeLinearSolver(Options("cholmod", "none"));
  solver->AnalyzePattern(A);
  if (!solver->Factorize(A)) {
    state.SkipWithError("factorisation failed");
    return;
  }
  VecX x(A.rows());
  for (auto _ : state) {
    const LinearSolveStats stats = solver->Solve(b, x);
    benchmark::DoNotOptimize(stats);
  }
  SetThreadCounter(state);
}
BENCHMARK(BM_DirectSolveOnly_Cholmod)
    ->Arg(14)
    ->Arg(26)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace gipsi
