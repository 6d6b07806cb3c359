// One implicit FEM step (the interactive set-up of issue 3): a 0.1 m cube of N³ hexahedra split
// into 5 tets each, x = 0 face fixed, gravity, E = 10 kPa, ν = 0.45, ρ = 1000 kg/m³,
// consistent mass, no damping, backward Euler with dt = 10 ms and one Newton iteration per step,
// the linear system solved to a relative residual of 1e-6. Reports per-step time, CG
// iterations and the split between assembly and solve, for steady-state steps: the first step
// (which also builds factorisations and multigrid hierarchies) is reported as first_step_ms.
// Run: ./build/release/bench/fem_bench --benchmark_repetitions=5
//        --benchmark_report_aggregates_only=true

#include <chrono>

#include <benchmark/benchmark.h>

#include "gipsi/base/json_node.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/tet_assembly.h"
#include "gipsi/numerics/sparse/linear_solver.h"
#include "gipsi/numerics/sparse/node_block_copy.h"
#include "gipsi/numerics/sparse/node_block_sgs.h"
#include "stream_triad.h"

namespace gipsi {
namespace {

const char* kPreconditioners[] = {"jacobi", "ic", "cholesky", "amg", "sgs"};

std::shared_ptr<const SolidMaterial> Law(const char* name) {
  static TypeRegistry registry;
  static const bool registered = (RegisterSolidLaws(registry), true);
  (void)registered;
  const std::string text =
      std::string(R"({"law": ")") + name + R"(", "youngs_modulus": 1e4, "poisson_ratio": 0.45})";
  const JsonDocument doc = JsonDocument::Parse(text, "bench");
  return registry.CreateMaterialAs<SolidMaterial>(doc.root(), "solid");
}

void BM_ImplicitStep(benchmark::State& state, const char* law) {
  const int cells = static_cast<int>(state.range(0));
  auto mesh = std::make_shared<const Mesh>(
      MakeTetBox(Vec3::Zero(), Vec3(0.1, 0.1, 0.1), {cells, cells, cells}, HexSplit::kFive));
  FemParams params;
  params.material = Law(law);
  params.scheme = ImplicitSchemeKind::kBackwardEuler;
  params.newton.max_iterations = 1;
  params.newton.fixed_iterations = true;
  params.newton.line_search = false;
  params.linear_solver.type = "cg";
  params.linear_solver.preconditioner = kPreconditioners[state.range(1)];
  params.linear_solver.tolerance = 1e-6;
  FemSolid fem("cube", mesh, params);
  for (Index v = 0; v < fem.boundary().num_vertices(); ++v)
    if (mesh->nodes(0, fem.boundary().vertex_to_node[static_cast<std::size_t>(v)]) == 0)
      fem.boundary_conditions().Fix(v);
  // The first step builds what later steps reuse (the symbolic analysis, the first CHOLMOD
  // factorisation, the AMG hierarchy): timed on its own, outside the steady-state loop.
  const auto first_start = std::chrono::steady_clock::now();
  std::int64_t failures = fem.Step(0.01).ok() ? 0 : 1;
  const double first_step =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - first_start).count();
  const FemProfile before = fem.profile();
  for (auto _ : state) {
    const StepStatus status = fem.Step(0.01);
    if (!status.ok()) ++failures;
    benchmark::DoNotOptimize(status);
  }
  const FemProfile& p = fem.profile();
  const double steps = static_cast<double>(p.steps - before.steps);
  state.counters["tets"] = static_cast<double>(fem.num_elements());
  state.counters["cg_its"] =
      static_cast<double>(p.linear_iterations - before.linear_iterations) / steps;
  state.counters["assembly_ms"] = 1e3 * (p.assembly_seconds - before.assembly_seconds) / steps;
  state.counters["solve_ms"] = 1e3 * (p.solve_seconds - before.solve_seconds) / steps;
  state.counters["failed_steps"] = static_cast<double>(failures);
  state.counters["first_step_ms"] = 1e3 * first_step;
}

// Preconditioners: 0 Jacobi, 1 incomplete Cholesky, 2 lagged CHOLMOD factorisation, 3 lagged
// smoothed-aggregation AMG, 4 symmetric block Gauss-Seidel ("sgs", the default). Eigen's incomplete
// Cholesky refactorises every step and costs more than it saves on the larger meshes.
void Sizes(benchmark::internal::Benchmark* b) {
  for (int n : {10, 16, 25}) b->Args({n, 3});
  for (int n : {10, 16, 25}) b->Args({n, 2});
  for (int n : {10, 16, 25}) b->Args({n, 0});
  for (int n : {10, 16, 25}) b->Args({n, 4});
  b->Args({10, 1});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}
BENCHMARK_CAPTURE(BM_ImplicitStep, corotational, "Corotational")->Apply(Sizes);
BENCHMARK_CAPTURE(BM_ImplicitStep, neo_hookean, "NeoHookean")->Apply(Sizes);

// The memory bandwidth of the product with the FEM tangent, beside a STREAM triad measured in
// the same run: second argument 0 is NodeBlockSpMV on the compressed columns (what CG with the
// lagged CHOLMOD factor uses), 1 the block-row copy NodeBlockCopy (Jacobi-CG and the AMG). The
// tangent is the corotational stiffness of the benchmark cube at rest (the values do not change the
// traffic). Bytes as for the triad, each array element read or written once: 8 B per nonzero, one 4
// B row index per 3×3 block, 4 B per column pointer (the copy reads one block start per node
// instead of three column pointers: counted the same, an overcount of 8 B per node), 8 B per
// entry of x and of y.
void BM_StreamTriad(benchmark::State& state) { RunStreamTriad(state); }
BENCHMARK(BM_StreamTriad)->UseRealTime()->Unit(benchmark::kMillisecond);

// The corotational stiffness of the benchmark cube of cells³ hexahedra at rest, into K; false
// (and the benchmark skipped) if it has no node-block pattern.
bool RestTangent(benchmark::State& state, int cells, SparseMatrix& K) {
  auto mesh = std::make_shared<const Mesh>(
      MakeTetBox(Vec3::Zero(), Vec3(0.1, 0.1, 0.1), {cells, cells, cells}, HexSplit::kFive));
  FemParams params;
  params.material = Law("Corotational");
  const FemSolid fem("cube", mesh, params);
  if (!fem.CalcStiffness(Eigen::Map<const VecX>(mesh->nodes.data(), mesh->nodes.size()), K) ||
      !HasNodeBlockPattern(K)) {
    state.SkipWithError("no node-block tangent");
    return false;
  }
  return true;
}

void BM_TangentSpMV(benchmark::State& state) {
  SparseMatrix K;
  if (!RestTangent(state, static_cast<int>(state.range(0)), K)) return;
  const VecX x = VecX::Ones(K.cols());
  VecX y(K.rows());
  NodeBlockCopy copy;
  if (state.range(1)) copy.Assign(K);
  for (auto _ : state) {
    if (state.range(1))
      copy.Multiply(x, y);
    else
      NodeBlockSpMV(K, x, y);
    benchmark::DoNotOptimize(y.data());
    benchmark::ClobberMemory();
  }
  const std::int64_t nnz = K.nonZeros();
  const std::int64_t bytes = 8 * nnz + 4 * (nnz / 9) + 4 * (K.cols() + 1) + 16 * K.rows();
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * bytes);
  state.counters["rows"] = static_cast<double>(K.rows());
  state.counters["nnz"] = static_cast<double>(nnz);
  state.counters["MB"] = 1e-6 * static_cast<double>(bytes);
}
BENCHMARK(BM_TangentSpMV)
    ->ArgsProduct({{10, 16, 25}, {0, 1}})
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);

// The sweeps of CG with symmetric block Gauss-Seidel (node_block_sgs.h) on the corotational
// tangent of the benchmark cube at rest, one domain, one thread: second argument 0 the backward
// sweep, 1 the forward sweep, 2 the update, 3 the update that also computes the residual, 4 the
// node-block product (NodeBlockCopy, for comparison). A CG iteration runs the first two and one
// of the updates.
void BM_SgsSweep(benchmark::State& state) {
  SparseMatrix K;
  if (!RestTangent(state, static_cast<int>(state.range(0)), K)) return;
  // The rest tangent is singular (no constraints): add a mass-like diagonal to make it SPD.
  for (Index i = 0; i < K.rows(); ++i) K.coeffRef(i, i) += 1.0;
  NodeBlockCopy copy;
  copy.Assign(K);
  NodeBlockSgs sgs;
  sgs.AssignPattern(K, 1);
  if (!sgs.Factorize(K)) {
    state.SkipWithError("diagonal block not SPD");
    return;
  }
  VecX x = VecX::Zero(K.rows()), r = VecX::Ones(K.rows()), y(K.rows());
  (void)sgs.Start(r.data(), 0);
  sgs.Backward(0.0, 0);
  (void)sgs.Forward(0);
  for (auto _ : state) {
    switch (state.range(1)) {
      case 0:
        sgs.Backward(0.5, 0);
        break;
      case 1:
        benchmark::DoNotOptimize(sgs.Forward(0));
        break;
      case 2:
        benchmark::DoNotOptimize(sgs.Update(1e-9, x.data(), false, 0));
        break;
      case 3:
        benchmark::DoNotOptimize(sgs.Update(1e-9, x.data(), true, 0));
        break;
      default:
        copy.Multiply(r, y);
    }
    benchmark::ClobberMemory();
  }
  state.counters["nodes"] = static_cast<double>(copy.nodes());
}
BENCHMARK(BM_SgsSweep)
    ->ArgsProduct({{16, 25}, {0, 1, 2, 3, 4}})
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);

// The element kernel alone: P and the 12×12 stiffness of 20,480 elements (the 20k-tet cube
// under a rotation and a stretch), element by element (second argument 0) or in batches of
// four lanes (1; with the AVX or generic kernels as GIPSI_SIMD says). Reports elements per
// second (items_per_second).
void BM_ElementKernel(benchmark::State& state, const char* law_name) {
  auto mesh = std::make_shared<const Mesh>(
      MakeTetBox(Vec3::Zero(), Vec3(0.1, 0.1, 0.1), {16, 16, 16}, HexSplit::kFive));
  const TetAssembly assembly(*mesh);
  const auto law = Law(law_name);
  Mat3 deformation;
  deformation << 1.1, 0.05, 0.0, -0.03, 0.95, 0.02, 0.01, 0.0, 1.02;
  const Mat3 F =
      Eigen::AngleAxisd(0.6, Vec3(1, 2, -1).normalized()).toRotationMatrix() * deformation;
  const Index ne = assembly.num_elements();
  const bool batched = state.range(0) != 0;
  double sink = 0;
  for (auto _ : state) {
    if (batched) {
      ElementBatch batch;
      for (Index begin = 0; begin < ne; begin += ElementBatch::kLanes) {
        batch.count = static_cast<int>(std::min<Index>(ElementBatch::kLanes, ne - begin));
        for (int l = 0; l < batch.count; ++l)
          batch.SetInput(l, F, assembly.gradients(begin + l), assembly.volume(begin + l), {});
        law->ElementStressAndStiffnessBatch(batch);
        sink += batch.K[0][0];
      }
    } else {
      Mat3 P;
      Mat12 K;
      for (Index e = 0; e < ne; ++e) {
        if (law->ElementStressAndStiffness(F, {}, assembly.gradients(e), assembly.volume(e), P, K))
          sink += K(0, 0);
      }
    }
    benchmark::DoNotOptimize(sink);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * ne);  // elements
}
BENCHMARK_CAPTURE(BM_ElementKernel, corotational, "Corotational")
    ->Arg(0)
    ->Arg(1)
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_ElementKernel, neo_hookean, "NeoHookean")
    ->Arg(0)
    ->Arg(1)
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace gipsi
