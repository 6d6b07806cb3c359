#pragma once
/// @file
/// The STREAM triad a = b + s·c as a Google Benchmark body, shared by the benchmarks that
/// report a kernel's memory bandwidth beside it (sparse_bench, fem_bench): three arrays of
/// 8 Mi doubles (64 MiB each, 192 MiB in all: 6× the 32 MiB last-level cache of the project's
/// machine class), first touched by the threads that use them. Bytes: 3 × 8 B per element,
/// write-allocate traffic not counted (McCalpin's convention).

#include <cstddef>
#include <cstdint>
#include <memory>

#include <benchmark/benchmark.h>
#include <omp.h>

namespace gipsi {

inline void RunStreamTriad(benchmark::State& state) {
  const std::ptrdiff_t n = std::ptrdiff_t{8} << 20;
  std::unique_ptr<double[]> a(new double[static_cast<std::size_t>(n)]);
  std::unique_ptr<double[]> b(new double[static_cast<std::size_t>(n)]);
  std::unique_ptr<double[]> c(new double[static_cast<std::size_t>(n)]);
  double* __restrict pa = a.get();
  double* __restrict pb = b.get();
  double* __restrict pc = c.get();
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    pa[i] = 0.0;
    pb[i] = 1.0;
    pc[i] = 2.0;
  }
  const double s = 3.0;
  for (auto _ : state) {
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < n; ++i) pa[i] = pb[i] + s * pc[i];
    benchmark::DoNotOptimize(pa);
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * 3 * 8 * n);
  state.counters["threads"] = static_cast<double>(omp_get_max_threads());
}

}  // namespace gipsi
