// Step cost of the mass-spring tissue per integrator and mesh size, and of a barycentric field
// transfer. Run: ./build/release/bench/mass_spring_bench --benchmark_repetitions=5
// --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>

#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mapping.h"
#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {
namespace {

template <class Integrator>
void BM_MassSpringStep(benchmark::State& state) {
  const int cells = static_cast<int>(state.range(0));
  auto mesh = std::make_shared<const Mesh>(
      MakeTetBox(Vec3::Zero(), Vec3(0.1, 0.1, 0.1), {cells, cells, cells}));
  MassSpring object("cube", mesh, MassSpringParams{}, std::make_unique<Integrator>());
  for (Index v = 0; v < object.boundary().num_vertices(); ++v)
    if (mesh->nodes(2, object.boundary().vertex_to_node[static_cast<std::size_t>(v)]) > 0.0999)
      object.boundary_conditions().Fix(v);
  for (auto _ : state) {
    StepStatus status = object.Step(1e-5);
    benchmark::DoNotOptimize(status);
  }
  state.counters["nodes"] = static_cast<double>(object.num_nodes());
  state.counters["springs"] = static_cast<double>(object.num_springs());
  state.counters["springs/s"] = benchmark::Counter(
      static_cast<double>(object.num_springs()) * static_cast<double>(state.iterations()),
      benchmark::Counter::kIsRate);
}
BENCHMARK_TEMPLATE(BM_MassSpringStep, SymplecticEuler)->Arg(5)->Arg(10)->Arg(20);
BENCHMARK_TEMPLATE(BM_MassSpringStep, ExplicitEuler)->Arg(10);
BENCHMARK_TEMPLATE(BM_MassSpringStep, RungeKutta4)->Arg(10);

void BM_BarycentricTransfer(benchmark::State& state) {
  const int cells = static_cast<int>(state.range(0));
  Mesh coarse = MakeTetBox(Vec3::Zero(), Vec3::Ones(), {cells, cells, cells});
  Mesh fine = MakeTetBox(Vec3::Zero(), Vec3::Ones(), {2 * cells, 2 * cells, 2 * cells});
  PointMap map = PointMap::BarycentricInTets(coarse.nodes, coarse.tets, fine.nodes);
  Eigen::MatrixXd source = Eigen::MatrixXd::Random(3, coarse.num_nodes());
  Eigen::MatrixXd target(3, fine.num_nodes());
  for (auto _ : state) {
    map.Apply(source, target);
    benchmark::DoNotOptimize(target.data());
  }
  state.counters["targets"] = static_cast<double>(fine.num_nodes());
}
BENCHMARK(BM_BarycentricTransfer)->Arg(10)->Arg(20);

void BM_BarycentricBuild(benchmark::State& state) {
  const int cells = static_cast<int>(state.range(0));
  Mesh coarse = MakeTetBox(Vec3::Zero(), Vec3::Ones(), {cells, cells, cells});
  Mesh fine = MakeTetBox(Vec3::Zero(), Vec3::Ones(), {2 * cells, 2 * cells, 2 * cells});
  for (auto _ : state) {
    PointMap map = PointMap::BarycentricInTets(coarse.nodes, coarse.tets, fine.nodes);
    benchmark::DoNotOptimize(map);
  }
}
BENCHMARK(BM_BarycentricBuild)->Arg(10)->Arg(20)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace gipsi
