// Strong scaling of the distributed monodomain (parallel/distributed_monodomain.h): the
// N-version slab (20 × 7 × 3 mm, ten Tusscher-Panfilov 2006 epicardial cells, Niederer et al.
// 2011) at any resolution, stepped on every rank of MPI_COMM_WORLD. Prints one line of
// figures: time per step (median, min and max over the timed steps, each ended by a barrier so
// the slowest rank counts), its split (cell models, diffusion, tracking; rank 0's), diffusion
// iterations per step, set-up time (partition + assembly), and the peak resident memory per
// rank (VmHWM) with the bytes per tet it makes. Each rank makes only its block of the slab
// (MakeTetBoxBlock) and the partitioner cuts it from the blocks, so no rank holds the whole
// mesh; --whole-mesh makes the whole slab on every rank first (what a scene run does).
//
//   mpiexec -np 2 build/release/bench/ep_scaling_bench --cells 160 56 24 --steps 200
//   build/release/bench/ep_scaling_bench --cells 160 56 24 --serial   (the serial Monodomain)
//
// Options: --cells NX NY NZ (hexahedra along the slab, 6 tets each; default 80 28 12, 161k
// tets), --steps N timed steps (default 100) after --warmup N (default 10), --pc jacobi|amg|
// hypre (default jacobi), --tolerance (default 1e-8, the scenes'), --serial (one rank: the
// serial object instead, for the baseline), --whole-mesh. Run with OMP_NUM_THREADS=1 per rank
// unless measuring threads within ranks.

#include <mpi.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/models/ep/monodomain.h"
#include "gipsi/models/ep/ten_tusscher_panfilov_2006.h"
#include "gipsi/parallel/distributed_monodomain.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/parallel_session.h"
#include "slab_cli.h"

namespace {

using gipsi::Index;

using gipsi::bench::Median;
using gipsi::bench::PeakResidentBytes;

struct Options {
  int nx = 80, ny = 28, nz = 12;
  int steps = 100, warmup = 10;
  std::string pc = "jacobi";
  double tolerance = 1e-8;
  bool serial = false;
  bool whole_mesh = false;
};

// Exits 2 with CLI11's message on a bad command line (PETSc options such as -log_view pass
// through as extras: PETSc reads them).
Options Parse(int argc, char** argv) {
  Options o;
  std::array<int, 3> cells = {o.nx, o.ny, o.nz};
  CLI::App app{"Strong scaling of the distributed monodomain on the N-version slab"};
  app.allow_extras();
  gipsi::bench::AddSlabCells(app, cells);
  app.add_option("--steps", o.steps, "Timed steps")->check(CLI::Range(1, 100000000));
  app.add_option("--warmup", o.warmup, "Untimed steps first")->check(CLI::NonNegativeNumber);
  app.add_option("--pc", o.pc, "Preconditioner")->check(CLI::IsMember({"jacobi", "amg", "hypre"}));
  app.add_option("--tolerance", o.tolerance, "CG's relative residual")->check(CLI::PositiveNumber);
  app.add_flag("--serial", o.serial, "The serial Monodomain instead (one rank)");
  app.add_flag("--whole-mesh", o.whole_mesh,
               "Every rank makes the whole slab before the cut (as scene runs read meshes)");
  gipsi::bench::ParseOrExit(app, argc, argv);
  o.nx = cells[0];
  o.ny = cells[1];
  o.nz = cells[2];
  return o;
}

gipsi::EpTissueParams SlabParams(const Options& o) {
  gipsi::EpTissueParams p;
  p.cell = std::make_shared<gipsi::TenTusscherPanfilov2006>();
  p.sigma_longitudinal = 0.17 * 0.62 / (0.17 + 0.62);
  p.sigma_transverse = 0.019 * 0.24 / (0.019 + 0.24);
  p.fibre = gipsi::Vec3::UnitX();
  p.surface_to_volume = 1.4e5;
  p.capacitance = 0.01;
  p.linear.preconditioner = o.pc;
  p.linear.tolerance = o.tolerance;
  gipsi::StimulusSpec corner;
  corner.name = "corner";
  corner.region = gipsi::BoxRegion{gipsi::Vec3::Constant(-1e-6), gipsi::Vec3::Constant(0.0015001)};
  corner.amplitude = 50000.0 / 1400.0;
  corner.pulses.duration = 2.0;
  p.stimuli.push_back(corner);
  return p;
}

int Main(int argc, char** argv) {
  const Options o = Parse(argc, argv);
  const MPI_Comm world = gipsi::ParallelSession::world();
  const int rank = gipsi::ParallelSession::rank(world);
  const int size = gipsi::ParallelSession::size(world);
  if (o.serial && size > 1) {
    if (rank == 0) std::fprintf(stderr, "ep_scaling_bench: --serial runs on one rank\n");
    return 2;
  }
  const double t0 = MPI_Wtime();
  std::shared_ptr<gipsi::Mesh> whole;
  gipsi::MeshBlock block;
  if (o.serial || o.whole_mesh)
    whole = std::make_shared<gipsi::Mesh>(gipsi::bench::SlabMesh(o.nx, o.ny, o.nz));
  else
    block = gipsi::MakeTetBoxBlock(gipsi::Vec3::Zero(), gipsi::bench::kSlabSize, {o.nx, o.ny, o.nz},
                                   gipsi::HexSplit::kSix, rank, size);
  const double t_mesh = MPI_Wtime() - t0;
  const std::int64_t num_tets = whole ? whole->num_tets() : block.num_tets;
  const std::int64_t num_nodes = whole ? whole->num_nodes() : block.num_nodes;
  std::unique_ptr<gipsi::EpTissue> tissue;
  std::string solver = "serial " + o.pc;
  if (o.serial) {
    gipsi::EpTissueParams p = SlabParams(o);
    if (o.pc == "amg") p.linear.preconditioner = "jacobi";  // the serial AMG is for 3×3 blocks
    tissue = std::make_unique<gipsi::Monodomain>("slab", whole, p);
  } else {
    auto d =
        whole ? std::make_unique<gipsi::DistributedMonodomain>("slab", *whole, SlabParams(o), world)
              : std::make_unique<gipsi::DistributedMonodomain>(
                    "slab", gipsi::PartitionMeshBlocks(block, world), SlabParams(o), world);
    block = {};
    solver = d->solver_name();
    tissue = std::move(d);
  }
  MPI_Barrier(world);
  const double t_setup = MPI_Wtime() - t0 - t_mesh;
  const double dt = 1e-5;  // 0.01 ms
  std::vector<double> times;
  long iterations = 0;
  for (int s = 0; s < o.warmup + o.steps; ++s) {
    const double start = MPI_Wtime();
    const gipsi::StepStatus status = tissue->Step(dt);
    MPI_Barrier(world);
    if (!status.ok()) {
      if (rank == 0) std::fprintf(stderr, "step %d failed: %s\n", s, status.what);
      return 3;
    }
    if (s >= o.warmup) {
      times.push_back(MPI_Wtime() - start);
      iterations += tissue->state().last_iterations;
    }
  }
  double phases[3] = {0, 0, 0};
  for (const auto& entry : tissue->ProfileBreakdown()) {
    if (entry.name.rfind("reaction (", 0) == 0) phases[0] = entry.value;
    if (entry.name.rfind("diffusion (", 0) == 0) phases[1] = entry.value;
    if (entry.name.rfind("activation", 0) == 0) phases[2] = entry.value;
  }
  double memory[2] = {PeakResidentBytes(), PeakResidentBytes()};
  MPI_Allreduce(MPI_IN_PLACE, &memory[0], 1, MPI_DOUBLE, MPI_MAX, world);
  MPI_Allreduce(MPI_IN_PLACE, &memory[1], 1, MPI_DOUBLE, MPI_SUM, world);
  if (rank == 0) {
    const auto tets = static_cast<double>(num_tets);
    std::printf(
        "ranks %d  tets %.0f  nodes %ld  solver %s  step median %.2f ms (min %.2f, max %.2f)  "
        "split (rank 0, all steps) cells %.1f%% diffusion %.1f%% tracking %.1f%%  "
        "iterations/step %.2f  mesh (%s) %.2f s  setup %.2f s  peak RSS/rank %.0f MB (max), "
        "%.0f B/tet over all ranks\n",
        size, tets, static_cast<long>(num_nodes), solver.c_str(), 1e3 * Median(times),
        1e3 * *std::min_element(times.begin(), times.end()),
        1e3 * *std::max_element(times.begin(), times.end()),
        100 * phases[0] / (phases[0] + phases[1] + phases[2]),
        100 * phases[1] / (phases[0] + phases[1] + phases[2]),
        100 * phases[2] / (phases[0] + phases[1] + phases[2]),
        static_cast<double>(iterations) / o.steps, whole ? "whole on every rank" : "in blocks",
        t_mesh, t_setup, memory[0] / 1e6, memory[1] / tets);
  }
  tissue.reset();  // before PETSc finalises
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  return gipsi::bench::RunBench("ep_scaling_bench", argc, argv, Main);
}
