// Node-steps per second of each cell model on one core: Step over 1e5 and 1e6 nodes whose
// states are spread over an action potential (as in a tissue during a wave: about a third of
// the nodes depolarised), no stimulus. Run:
//   ./build/release/bench/cell_models_bench --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "gipsi/base/json_node.h"
#include "gipsi/models/ep/cell_models.h"
#include "gipsi/models/ep/single_cell.h"

namespace gipsi {
namespace {

std::shared_ptr<const CellModel> Model(const std::string& json) {
  TypeRegistry registry;
  RegisterCellModels(registry);
  JsonDocument doc = JsonDocument::Parse(json, "bench");
  return CreateCellModel(registry, doc.root());
}

/// `num_nodes` cells in the states of one paced beat (1000 ms sampled every 0.1 ms), node i
/// taking the sample at the same fraction of the beat as i of the nodes.
CellStates SpreadOverABeat(const CellModel& model, std::size_t num_nodes, double dt) {
  std::vector<std::vector<double>> samples;
  PacingProtocol protocol;
  protocol.dt = dt;
  protocol.stim_amplitude = model.default_stimulus().amplitude;
  protocol.stim_duration = model.default_stimulus().duration;
  protocol.record_every = 0;
  PaceSingleCell(
      model, protocol, {},
      [&samples](double, std::span<const double> s) { samples.emplace_back(s.begin(), s.end()); },
      std::llround(0.1 / dt));
  CellStates states(model, num_nodes);
  for (std::size_t i = 0; i < num_nodes; ++i)
    states.SetNode(i, samples[i * samples.size() / num_nodes]);
  return states;
}

void BM_CellModelStep(benchmark::State& state, const std::string& json, double dt) {
  const auto num_nodes = static_cast<std::size_t>(state.range(0));
  auto model = Model(json);
  CellStates states = SpreadOverABeat(*model, num_nodes, dt);
  for (auto _ : state) {
    model->Step(states.view(), 0, num_nodes, dt);
    benchmark::DoNotOptimize(states.var(0));
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) *
                          static_cast<std::int64_t>(num_nodes));
  state.counters["states"] = model->num_states();
}

BENCHMARK_CAPTURE(BM_CellModelStep, AlievPanfilov, R"({"model": "AlievPanfilov"})", 0.05)
    ->Arg(100000)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_CellModelStep, MitchellSchaeffer, R"({"model": "MitchellSchaeffer"})", 0.05)
    ->Arg(100000)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_CellModelStep, FitzHughNagumo, R"({"model": "FitzHughNagumo"})", 0.05)
    ->Arg(100000)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_CellModelStep, TenTusscherPanfilov2006,
                  R"({"model": "TenTusscherPanfilov2006"})", 0.01)
    ->Arg(100000)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_CellModelStep, TenTusscherPanfilov2006_NoTables,
                  R"({"model": "TenTusscherPanfilov2006", "lookup_tables": false})", 0.01)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace gipsi
