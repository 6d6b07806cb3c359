// The Land et al. (2015) beam (problem 1: 10 × 1 × 1 mm Guccione, C = 2 kPa, b_f 8, b_t 2,
// b_fs 4, clamped at x = 0, 4 Pa follower pressure underneath) solved quasi-statically in 8
// load steps, on 10n × n × n cubes of 6 tets: the locking-free MixedSolid (Taylor–Hood P2–P1,
// fully incompressible, UMFPACK) beside today's penalty FemSolid (P1, κ = 1000 C, CHOLMOD with
// its LDLᵀ fallback). One iteration = the whole solve from the rest state. Counters: tip
// displacement of (10, 0.5, 1) mm (the benchmark's codes: 3.17 mm), Newton iterations, time
// per Newton iteration (set-up and solve over the iterations), unknowns. P1 locks at this κ, so the
// two do not reach equal accuracy at any mesh here: compare the time to reach a given tip error
// (docs/incompressible.md). Run: ./build/release/bench/incompressible_bench
// --benchmark_repetitions=3
//        --benchmark_report_aggregates_only=true

#include <chrono>
#include <memory>
#include <string>

#include <benchmark/benchmark.h>

#include "gipsi/base/json_node.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/mixed_solid.h"

namespace gipsi {
namespace {

std::shared_ptr<const SolidMaterial> Guccione(double kappa_over_c) {
  static TypeRegistry registry;
  static const bool registered = (RegisterSolidLaws(registry), true);
  (void)registered;
  const std::string text = R"({"law": "Guccione", "C": 2000, "bf": 8, "bt": 2, "bfs": 4,
      "bulk_modulus": )" + std::to_string(2000 * kappa_over_c) +
                           "}";
  const JsonDocument doc = JsonDocument::Parse(text, "bench");
  return registry.CreateMaterialAs<SolidMaterial>(doc.root(), "solid");
}

std::shared_ptr<const Mesh> Beam(int n) {
  return std::make_shared<const Mesh>(
      MakeTetBox(Vec3::Zero(), Vec3(0.01, 0.001, 0.001), {10 * n, n, n}));
}

/// Clamp at x = 0 and 4 Pa on z = 0, through the boundary vertices and faces.
void Load(SimObject& object) {
  const BoundarySurface& b = object.boundary();
  const Points& x = object.domain().nodes;
  for (Index v = 0; v < b.num_vertices(); ++v)
    if (x(0, b.vertex_to_node[static_cast<std::size_t>(v)]) < 1e-12)
      object.boundary_conditions().Fix(v);
  for (Index f = 0; f < b.num_triangles(); ++f) {
    bool bottom = true;
    for (int i = 0; i < 3; ++i)
      bottom =
          bottom && x(2, b.vertex_to_node[static_cast<std::size_t>(b.triangles(i, f))]) < 1e-12;
    if (bottom) object.boundary_conditions().SetPressure(f, 4.0);
  }
}

/// z displacement of the P2 node at (10, 0.5, 1) mm [mm] (an edge node when n is odd).
double TipMm(const MixedSolid& solid) {
  const QuadraticTets& q = solid.quadratic_mesh();
  const Points u = solid.NodeDisplacements();
  for (Index i = 0; i < q.num_nodes(); ++i)
    if ((q.rest.col(i) - Vec3(0.01, 0.0005, 0.001)).norm() < 1e-12) return 1e3 * u(2, i);
  return -1;
}

/// z displacement of the vertex at (10, 0.5, 1) mm [mm].
double TipMm(const SimObject& object) {
  const Points& x = object.domain().nodes;
  for (Index i = 0; i < x.cols(); ++i)
    if ((x.col(i) - Vec3(0.01, 0.0005, 0.001)).norm() < 1e-12)
      return 1e3 * (object.domain_positions()(2, i) - x(2, i));
  return -1;
}

/// The mixed beam with linear solver `solver` ("umfpack" or "schur_gmres").
void LandBeamMixed(benchmark::State& state, const char* solver) {
  const int n = static_cast<int>(state.range(0));
  const auto mesh = Beam(n);
  double tip = 0, iterations = 0, unknowns = 0, seconds = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    MixedSolidParams params;
    params.material = Guccione(1000);
    params.incompressible = true;
    params.fibre = Vec3::UnitX();
    params.load_steps = 8;
    params.newton.tolerance = 1e-10;
    params.newton.max_iterations = 40;
    params.linear_solver.type = solver;
    MixedSolid solid("beam", mesh, params);
    Load(solid);
    const StepStatus status = solid.Step(1);
    if (!status.ok()) state.SkipWithError(status.what);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    tip = TipMm(solid);
    iterations = static_cast<double>(solid.total_newton_iterations());
    unknowns = static_cast<double>(solid.num_unknowns());
  }
  state.counters["tip_mm"] = tip;
  state.counters["newton_its"] = iterations;
  state.counters["unknowns"] = unknowns;
  state.counters["ms_per_it"] =
      1e3 * seconds / (iterations * static_cast<double>(state.iterations()));
}

void BM_LandBeamMixedP2P1(benchmark::State& state) { LandBeamMixed(state, "umfpack"); }
BENCHMARK(BM_LandBeamMixedP2P1)
    ->Arg(1)
    ->Arg(2)
    ->Arg(4)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// The same with GMRES and the block preconditioner (saddle_point_solver.h).
void BM_LandBeamMixedP2P1Schur(benchmark::State& state) { LandBeamMixed(state, "schur_gmres"); }
BENCHMARK(BM_LandBeamMixedP2P1Schur)
    ->Arg(1)
    ->Arg(2)
    ->Arg(4)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_LandBeamPenaltyP1(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto mesh = Beam(n);
  double tip = 0, iterations = 0, unknowns = 0, seconds = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    FemParams params;
    params.material = Guccione(1000);
    params.gravity = Vec3::Zero();
    params.scheme = ImplicitSchemeKind::kStatic;
    params.fibre = Vec3::UnitX();
    params.load_steps = 8;
    params.newton.tolerance = 1e-10;
    params.newton.max_iterations = 50;
    params.linear_solver.type = "cholmod";
    FemSolid solid("beam", mesh, params);
    Load(solid);
    const StepStatus status = solid.Step(1);
    if (!status.ok()) state.SkipWithError(status.what);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    tip = TipMm(solid);
    iterations = static_cast<double>(solid.profile().newton_iterations);
    unknowns = static_cast<double>(3 * solid.num_nodes());
  }
  state.counters["tip_mm"] = tip;
  state.counters["newton_its"] = iterations;
  state.counters["unknowns"] = unknowns;
  state.counters["ms_per_it"] =
      1e3 * seconds / (iterations * static_cast<double>(state.iterations()));
}
BENCHMARK(BM_LandBeamPenaltyP1)
    ->Arg(2)
    ->Arg(4)
    ->Arg(8)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace gipsi
