// What the kernel's step-retry policy costs per macro step, next to the macro step itself, on
// shipped scenes. With `failure_policy.max_halvings` > 0 the kernel copies the state of every
// object and connector into a snapshot it keeps (Coordinator::TakeSnapshot: state value types,
// gipsi/base/object_state.h) before every macro step, and restores it when the step fails.
// Until issue 18 it serialised the whole kernel instead (Kernel::SaveState into a byte string,
// and RestoreState, which also factorised the heart's kept Newton matrix again); that path is
// still what checkpoints use, and it is measured beside the snapshots as the baseline.
//
//   BM_MacroStep/<scene>         one macro step of the scene (no outputs attached)
//   BM_RollbackSave/<scene>      the snapshot copied before each macro step
//   BM_RollbackRestore/<scene>   restoring it (only when a step fails)
//   BM_CheckpointSave/<scene>    the serialised state (the retry's cost before issue 18)
//   BM_CheckpointRestore/<scene> restoring it
// Counters: state_bytes (the serialised state's size), macro_dt.

#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <utility>

#include "gipsi/base/error.h"
#include "gipsi/base/object_state.h"
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
  Coordinator& coordinator = loaded.kernel->coordinator();
  const std::unique_ptr<ObjectState> snapshot = coordinator.NewSnapshot();  // kept, as the kernel
  for (auto _ : state) {
    coordinator.TakeSnapshot(*snapshot);
    benchmark::ClobberMemory();
  }
}

void BM_RollbackRestore(benchmark::State& state, const std::string& scene, double warm) {
  Scene loaded = Loaded(scene, warm);
  Coordinator& coordinator = loaded.kernel->coordinator();
  const std::unique_ptr<ObjectState> snapshot = coordinator.NewSnapshot();
  for (auto _ : state) {
    coordinator.RestoreSnapshot(*snapshot);
    benchmark::ClobberMemory();
  }
}

void BM_CheckpointSave(benchmark::State& state, const std::string& scene, double warm) {
  Scene loaded = Loaded(scene, warm);
  std::size_t bytes = 0;
  for (auto _ : state) {
    StateWriter out;  // a fresh writer per macro step, as the retry did
    loaded.kernel->SaveState(out);
    bytes = out.bytes().size();
    benchmark::DoNotOptimize(out.bytes().data());
  }
  state.counters["state_bytes"] = static_cast<double>(bytes);
}

void BM_CheckpointRestore(benchmark::State& state, const std::string& scene, double warm) {
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
// contraction; the mass-spring heart; the FEM liver (10 ms macro steps); the EP slab on tets;
// the liver palpated by a synchronous haptic probe, in contact (the haptic pair's state: the
// tick, the device and both lock-free buffers with their local models).
// Each scene gets the five benchmarks, named BM_MacroStep/<id> and so on.
const bool kRegistered = [] {
  struct Case {
    const char* id;
    const char* scene;
    double warm;
  };
  using Fn = void (*)(benchmark::State&, const std::string&, double);
  const std::pair<const char*, Fn> kinds[] = {{"BM_MacroStep", BM_MacroStep},
                                              {"BM_RollbackSave", BM_RollbackSave},
                                              {"BM_RollbackRestore", BM_RollbackRestore},
                                              {"BM_CheckpointSave", BM_CheckpointSave},
                                              {"BM_CheckpointRestore", BM_CheckpointRestore}};
  for (const Case& c :
       {Case{"heart", "heart.json", 0.1}, Case{"heart_mass_spring", "heart_mass_spring.json", 0.1},
        Case{"liver_fem", "hanging_liver_fem.json", 0.1},
        Case{"slab_ep_0_5mm", "slab_ep_0.5mm.json", 0.005},
        Case{"palpation", "liver_palpation.json", 1.25}})
    for (const auto& [kind, fn] : kinds)
      benchmark::RegisterBenchmark((std::string(kind) + "/" + c.id).c_str(), fn,
                                   std::string(c.scene), c.warm)
          ->Unit(benchmark::kMicrosecond);
  return true;
}();

}  // namespace
}  // namespace gipsi
