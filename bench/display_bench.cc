// Display managers: the per-frame cost, on the simulation thread, of filling and publishing the
// render buffers of a block's boundary surface (40 x 40 x 40 cells: 9,602 boundary vertices,
// 19,200 triangles), solid and coloured by displacement magnitude.

#include <benchmark/benchmark.h>

#include "gipsi/base/latest_value.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/display_manager.h"

namespace gipsi::viz {
namespace {

void BM_FillAndPublishBlockSurface(benchmark::State& state) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(R"({
    "meshes": {"block": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1],
                         "cells": [40, 40, 40]}},
    "objects": {"block": {"type": "MassSpring", "domain": "block", "density": 1000,
      "stiffness": 100, "integrator": "SymplecticEuler", "dt": 0.001}},
    "schedule": {"end": 1}
  })",
                                    "bench.json", ".", registry);
  std::vector<std::pair<std::string, ColorSpec>> colors;
  if (state.range(0) == 1) {
    ColorSpec spec;
    spec.field = "displacement";
    colors.emplace_back("block", spec);
  }
  SceneDisplay display(*scene.kernel, colors);
  LatestValue<FrameBuffers> frames;
  for (auto _ : state) {
    display.Fill(0, frames.back());
    frames.Publish();
  }
  display.Fill(0, frames.back());
  const auto& surface = frames.back().surfaces.at(0);
  state.counters["vertices"] = double(surface.num_vertices());
  state.counters["triangles"] = double(surface.num_triangles());
  state.SetLabel(state.range(0) == 1 ? "coloured by |displacement|" : "solid");
}
BENCHMARK(BM_FillAndPublishBlockSurface)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace gipsi::viz
