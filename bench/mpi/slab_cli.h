#pragma once
// What the MPI benches share: the N-version slab (20 × 7 × 3 mm) and its size in hexahedra
// (--cells NX NY NZ), the peak resident memory, a median and timings over the ranks, a parse
// that exits 2 with CLI11's message on a bad command line (0 after --help), and a main that
// reports an error on every rank and ends them all.

#include <CLI/CLI.hpp>

#include <mpi.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>
#include <vector>

#include "gipsi/geometry/generators.h"
#include "gipsi/parallel/parallel_session.h"

namespace gipsi::bench {

// Peak resident memory of this process [bytes] (VmHWM of /proc/self/status).
inline double PeakResidentBytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return 1024.0 * std::atof(line.c_str() + 6);
  return 0;
}

// The median of `v` (the upper one of an even count; 0 for none).
inline double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

// Median over `batches` batches of the slowest rank's time per call of `call` [s], each batch
// `reps` calls after `reps` calls of warm-up. Collective.
template <class Call>
double SlowestRankPerCall(MPI_Comm comm, int batches, int reps, Call call) {
  for (int r = 0; r < reps; ++r) call();  // warm-up
  std::vector<double> times;
  for (int b = 0; b < batches; ++b) {
    MPI_Barrier(comm);
    const double start = MPI_Wtime();
    for (int r = 0; r < reps; ++r) call();
    double t = (MPI_Wtime() - start) / reps;
    MPI_Allreduce(MPI_IN_PLACE, &t, 1, MPI_DOUBLE, MPI_MAX, comm);
    times.push_back(t);
  }
  return Median(times);
}

// The slowest rank's time of one call of `call` [s]. Collective.
template <class Call>
double TimeOnce(MPI_Comm comm, Call call) {
  MPI_Barrier(comm);
  const double start = MPI_Wtime();
  call();
  double t = MPI_Wtime() - start;
  MPI_Allreduce(MPI_IN_PLACE, &t, 1, MPI_DOUBLE, MPI_MAX, comm);
  return t;
}

// Adds --cells NX NY NZ (hexahedra along the 20 × 7 × 3 mm slab, 6 tets each) into `cells`.
inline void AddSlabCells(CLI::App& app, std::array<int, 3>& cells) {
  app.add_option("--cells", cells, "Hexahedra along the slab (6 tets each)")
      ->check(CLI::Range(1, 100000));
}

// The slab's size [m].
inline const Vec3 kSlabSize{0.020, 0.007, 0.003};

// The slab cut into nx × ny × nz hexahedra of 6 tets each.
inline Mesh SlabMesh(int nx, int ny, int nz) {
  return MakeTetBox(Vec3::Zero(), kSlabSize, {nx, ny, nz});
}

inline void ParseOrExit(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints the message (or the help)
    std::exit(code == 0 ? 0 : 2);
  }
}

// Runs `run(argc, argv)` with MPI and PETSc started. A bad size (a mesh past the generator's
// limit, more ranks than tets) is reported by every rank and ends all of them, rather than
// terminate's core dump.
template <class Run>
int RunBench(const char* name, int argc, char** argv, Run run) {
  ParallelSession session(&argc, &argv);  // MPI_Abort below needs MPI alive
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    MPI_Abort(MPI_COMM_WORLD, 1);
    return 1;
  }
}

}  // namespace gipsi::bench
