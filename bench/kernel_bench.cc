// What the kernel's step-retry policy costs per macro step, next to the macro step itself, on
// shipped scenes: with `failure_policy.max_halvings` > 0 the kernel saves the complete state
// (Kernel::SaveState, every object and connector serialised into a byte string) before every
// macro step, and restores it (Kernel::RestoreState) when the step fails. Issue 18 replaces
// the serialisation by a copy of state values; these are the figures it is measured against.
//
//   BM_MacroStep/<scene>       one macro step of the scene (no outputs attached)
//   BM_RollbackSave/<scene>    the roll-back snapshot taken before each macro step
//   BM_RollbackRestore/<scene> restoring it (only when a step fails)
// Counters: state_bytes (the snapshot's size), macro_dt.

#include <benchmark/benchmark.h>

#include <string>
#include <utility>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/core/kernel.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"

namespace gipsi {
namespace {

/// `scene` from scenes/, run to `warm` seconds (so solvers hold their kept state, e.g. the
/// heart's factorisation in contraction).
Scene Loaded(const std::string& scene, double warm) {
  static TypeRegistry registry;
  if (!registry.objects.Contains("Heart")) RegisterBuiltins(registry);
  Scene loaded = LoadScene(std::string(GIPSI_BENCH_SCENES) + "/" + scene, registry);
  const RunResult run = loaded.kernel->Run(warm);
  if (!run.ok()) throw InputError(scene + ": " + run.diagnostic);
  return loaded;
}

void BM_MacroStep(benchmark::State& state, const std::string& scene, double warm) {
  Scene loaded = Loaded(scene, warm);
  Kernel& kernel = *loaded.kernel;
  for (auto _ : state) {
    const RunResult run = kernel.Run(kernel.time() + kernel.macro_dt());
    if (!run.ok()) {
      state.SkipWithError(run.diagnostic.c_str());
      break;
    }
  }
  state.counters["macro_dt"] = kernel.macro_dt();
}

void BM_RollbackSave(benchmark::State& state, const std::string& scene, double warm) {
  Scene loaded = Loaded(scene, warm);
  std::size_t bytes = 0;
  for (auto _ : state) {
    StateWriter out;  // as StepWithPolicy does: a fresh writer per macro step
    loaded.kernel->SaveState(out);
    bytes = out.bytes().size();
    benchmark::DoNotOptimize(out.bytes().data());
  }
  state.counters["state_bytes"] = static_cast<double>(bytes);
}

void BM_RollbackRestore(benchmark::State& state, const std::string& scene, double warm) {
  Scene loaded = Loaded(scene, warm);
  StateWriter out;
  loaded.kernel->SaveState(out);
  const std::string bytes = out.TakeBytes();
  for (auto _ : state) {
    StateReader in(bytes, "the roll-back state");
    loaded.kernel->RestoreState(in);
  }
  state.counters["state_bytes"] = static_cast<double>(bytes.size());
}

// The coupled heart (EP + FEM wall with its kept factorisation + cavity + blood), in its first
// contraction; the mass-spring heart; the FEM liver (10 ms macro steps); the EP slab on tets.
// Each scene gets the three benchmarks, named BM_MacroStep/<id> and so on.
const bool kRegistered = [] {
  struct Case {
    const char* id;
    const char* scene;
    double warm;
  };
  using Fn = void (*)(benchmark::State&, const std::string&, double);
  const std::pair<const char*, Fn> kinds[] = {{"BM_MacroStep", BM_MacroStep},
                                              {"BM_RollbackSave", BM_RollbackSave},
                                              {"BM_RollbackRestore", BM_RollbackRestore}};
  for (const Case& c :
       {Case{"heart", "heart.json", 0.1}, Case{"heart_mass_spring", "heart_mass_spring.json", 0.1},
        Case{"liver_fem", "hanging_liver_fem.json", 0.1},
        Case{"slab_ep_0_5mm", "slab_ep_0.5mm.json", 0.005}})
    for (const auto& [kind, fn] : kinds)
      benchmark::RegisterBenchmark((std::string(kind) + "/" + c.id).c_str(), fn,
                                   std::string(c.scene), c.warm)
          ->Unit(benchmark::kMicrosecond);
  return true;
}();

}  // namespace
}  // namespace gipsi
