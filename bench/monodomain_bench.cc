// One monodomain step of the Niederer et al. (2011) benchmark slab (20 × 7 × 3 mm, TTP06 epi,
// harmonic-mean conductivities, fibres along x) at 0.2 mm on P1 tets and on the FD grid, with
// a wave in flight (the slab is first run for 10 ms after the corner stimulus), reporting the
// reaction / diffusion split and the diffusion solver's iterations. Run:
//   OMP_WAIT_POLICY=passive ./build/release/bench/monodomain_bench
//     --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
// The whole 60 ms run is timed by the CLI: gipsi run scenes/slab_ep_0.2mm.json --profile

#include <benchmark/benchmark.h>

#include <memory>

#include "gipsi/base/json_node.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/models/ep/cell_models.h"
#include "gipsi/models/ep/grid_monodomain.h"
#include "gipsi/models/ep/monodomain.h"

namespace gipsi {
namespace {

// 50,000 µA/cm³ = 50,000 A/m³ for 2 ms into a 1.5 mm corner cube.
EpTissueParams SlabParams() {
  TypeRegistry registry;
  RegisterCellModels(registry);
  JsonDocument doc =
      JsonDocument::Parse(R"({"model": "TenTusscherPanfilov2006", "variant": "epi"})", "bench");
  EpTissueParams p;
  p.cell = CreateCellModel(registry, doc.root());
  p.sigma_longitudinal = 0.17 * 0.62 / (0.17 + 0.62);
  p.sigma_transverse = 0.019 * 0.24 / (0.019 + 0.24);
  p.fibre = Vec3::UnitX();
  p.reaction_dt = 1e-5;  // 0.01 ms
  p.stimuli.push_back({"corner", BoxRegion{Vec3::Constant(-1), Vec3::Constant(0.0015001)},
                       50000.0 / (p.surface_to_volume * p.capacitance), PulseTrain{0, 2}});
  return p;
}

const Vec3 kSlab(0.020, 0.007, 0.003);
const std::array<int, 3> kCells = {100, 35, 15};  // 0.2 mm

// Steps of `dt_ms`; the wave is started by 10 ms of steps outside the timing.
void RunSlab(benchmark::State& state, EpTissue& tissue, double dt_ms) {
  for (int k = 0; k < static_cast<int>(10 / dt_ms); ++k) (void)tissue.Step(1e-3 * dt_ms);
  const auto before = tissue.ProfileBreakdown();
  std::int64_t steps = 0;
  for (auto _ : state) {
    if (!tissue.Step(1e-3 * dt_ms).ok()) state.SkipWithError("step failed");
    ++steps;
  }
  const auto after = tissue.ProfileBreakdown();
  state.counters["reaction_ms"] = 1e3 * (after[0].value - before[0].value) / steps;
  state.counters["diffusion_ms"] = 1e3 * (after[1].value - before[1].value) / steps;
  state.counters["solver_its"] = (after[3].value - before[3].value) / steps;
  state.counters["nodes"] = static_cast<double>(tissue.num_nodes());
}

void BM_SlabStepTets(benchmark::State& state) {
  const double dt_ms = static_cast<double>(state.range(0)) / 100;
  Monodomain tissue("slab", std::make_shared<Mesh>(MakeTetBox(Vec3::Zero(), kSlab, kCells)),
                    SlabParams());
  RunSlab(state, tissue, dt_ms);
}

void BM_SlabStepGrid(benchmark::State& state) {
  const double dt_ms = static_cast<double>(state.range(0)) / 100;
  GridMonodomain tissue("slab", CartesianGrid{Vec3::Zero(), kSlab, kCells}, SlabParams());
  RunSlab(state, tissue, dt_ms);
}

// Argument: the step in hundredths of ms (1: 0.01 ms; 5: 0.05 ms with five reaction sub-steps).
BENCHMARK(BM_SlabStepTets)->Arg(1)->Arg(5)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SlabStepGrid)->Arg(1)->Arg(5)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace gipsi
