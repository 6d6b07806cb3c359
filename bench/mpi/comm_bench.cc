// What the distributed monodomain's step communicates, measured on this machine, for the
// weak-scaling model of docs/scale-out.md: the partition's surface (owned nodes, ghost nodes,
// neighbour ranks per rank, from parallel/mesh_partition.h on the N-version slab), the halo
// exchange of a ghosted vector on that partition (VecGhostUpdateBegin/End, what each CG
// iteration's MatMult and the ghost refresh after each solve do), and MPI_Allreduce of one and
// two doubles (what CG's dot products and norms do). Latencies are medians of batches, each
// batch timed on every rank and its slowest rank counted.
//
//   mpiexec -np 2 build/release/bench/comm_bench --cells 160 56 24
//   mpiexec -np 16 --oversubscribe build/release/bench/comm_bench --cells 80 28 12 --partition-only
//
// Every run prints the surface line and the MatMult line (what a product receives per rank,
// its time); the last line, the latencies, is left out with --partition-only.
//
// Options: --cells NX NY NZ (hexahedra along the 20 × 7 × 3 mm slab, 6 tets each; default 80
// 28 12), --batches N (default 50) of --reps N (default 200) exchanges each, --partition-only
// (the surface figures alone, no latencies: oversubscribed runs time the scheduler, not MPI).

#include <mpi.h>
#include <petscmat.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <vector>

#include "gipsi/geometry/generators.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/parallel_session.h"
#include "gipsi/parallel/petsc_check.h"
#include "slab_cli.h"

namespace {

struct Options {
  int nx = 80, ny = 28, nz = 12;
  int batches = 50, reps = 200;
  bool partition_only = false;
};

// Exits 2 with CLI11's message on a bad command line.
Options Parse(int argc, char** argv) {
  Options o;
  std::array<int, 3> cells = {o.nx, o.ny, o.nz};
  CLI::App app{"What the distributed monodomain's step communicates"};
  gipsi::bench::AddSlabCells(app, cells);
  app.add_option("--batches", o.batches, "Timed batches")->check(CLI::Range(1, 100000000));
  app.add_option("--reps", o.reps, "Calls per batch")->check(CLI::Range(1, 100000000));
  app.add_flag("--partition-only", o.partition_only, "The surface figures alone");
  gipsi::bench::ParseOrExit(app, argc, argv);
  o.nx = cells[0];
  o.ny = cells[1];
  o.nz = cells[2];
  return o;
}

// Median over batches of the slowest rank's time per call of `call` [s].
template <class Call>
double TimePerCall(const Options& o, MPI_Comm comm, Call call) {
  return gipsi::bench::SlowestRankPerCall(comm, o.batches, o.reps, call);
}

int Main(int argc, char** argv) {
  const Options o = Parse(argc, argv);
  const MPI_Comm world = gipsi::ParallelSession::world();
  const int rank = gipsi::ParallelSession::rank(world);
  const int size = gipsi::ParallelSession::size(world);
  const gipsi::Mesh whole = gipsi::bench::SlabMesh(o.nx, o.ny, o.nz);
  const gipsi::MeshPart part = gipsi::PartitionMesh(whole, world);

  // The surface: ghosts (local nodes owned by another rank) and the ranks that own them.
  std::vector<std::int64_t> firsts(static_cast<std::size_t>(size));
  MPI_Allgather(&part.first_owned, 1, MPI_INT64_T, firsts.data(), 1, MPI_INT64_T, world);
  std::vector<PetscInt> ghosts;
  std::set<int> neighbours;
  for (std::int64_t i = part.num_owned; i < part.num_local(); ++i) {
    const std::int64_t g = part.global[static_cast<std::size_t>(i)];
    ghosts.push_back(static_cast<PetscInt>(g));
    neighbours.insert(
        static_cast<int>(std::upper_bound(firsts.begin(), firsts.end(), g) - firsts.begin() - 1));
  }
  double mine[3] = {static_cast<double>(part.num_owned), static_cast<double>(ghosts.size()),
                    static_cast<double>(neighbours.size())};
  double high[3], sum[3];
  MPI_Allreduce(mine, high, 3, MPI_DOUBLE, MPI_MAX, world);
  MPI_Allreduce(mine, sum, 3, MPI_DOUBLE, MPI_SUM, world);
  if (rank == 0)
    std::printf(
        "ranks %d  tets %lld  nodes %lld  owned nodes/rank mean %.0f max %.0f  ghost nodes/rank "
        "mean %.0f max %.0f  neighbour ranks mean %.1f max %.0f  ghosts/owned^(2/3) mean %.2f\n",
        size, static_cast<long long>(whole.num_tets()), static_cast<long long>(whole.num_nodes()),
        sum[0] / size, high[0], sum[1] / size, high[1], sum[2] / size, high[2],
        sum[1] / size / std::cbrt(sum[0] / size * sum[0] / size));

  // The P1 pattern on this partition, assembled as the monodomain's operator is (each rank's
  // tets, COO, summed across ranks): its off-process columns are what a MatMult receives.
  std::vector<PetscInt> rows, columns;
  for (gipsi::Index t = 0; t < part.mesh->num_tets(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        rows.push_back(
            static_cast<PetscInt>(part.global[static_cast<std::size_t>(part.mesh->tets(a, t))]));
        columns.push_back(
            static_cast<PetscInt>(part.global[static_cast<std::size_t>(part.mesh->tets(b, t))]));
      }
  Mat k = nullptr;
  GIPSI_PETSC(MatCreate(world, &k));
  GIPSI_PETSC(MatSetSizes(k, static_cast<PetscInt>(part.num_owned),
                          static_cast<PetscInt>(part.num_owned), PETSC_DETERMINE, PETSC_DETERMINE));
  GIPSI_PETSC(MatSetType(k, MATMPIAIJ));
  GIPSI_PETSC(
      MatSetPreallocationCOO(k, static_cast<PetscCount>(rows.size()), rows.data(), columns.data()));
  std::vector<PetscScalar> ones(rows.size(), 1.0);
  GIPSI_PETSC(MatSetValuesCOO(k, ones.data(), ADD_VALUES));
  Mat diagonal_block = nullptr, off_block = nullptr;
  const PetscInt* off_columns = nullptr;
  GIPSI_PETSC(MatMPIAIJGetSeqAIJ(k, &diagonal_block, &off_block, &off_columns));
  PetscInt off_rows = 0, off_count = 0;
  GIPSI_PETSC(MatGetSize(off_block, &off_rows, &off_count));
  double received[2] = {static_cast<double>(off_count), static_cast<double>(off_count)};
  MPI_Allreduce(MPI_IN_PLACE, &received[0], 1, MPI_DOUBLE, MPI_SUM, world);
  MPI_Allreduce(MPI_IN_PLACE, &received[1], 1, MPI_DOUBLE, MPI_MAX, world);
  Vec x = nullptr, y = nullptr;
  GIPSI_PETSC(MatCreateVecs(k, &x, &y));
  GIPSI_PETSC(VecSet(x, 1.0));
  const double product = o.partition_only ? 0.0 : TimePerCall(o, world, [&] { MatMult(k, x, y); });
  GIPSI_PETSC(VecDestroy(&x));
  GIPSI_PETSC(VecDestroy(&y));
  GIPSI_PETSC(MatDestroy(&k));
  if (rank == 0)
    std::printf(
        "ranks %d  MatMult receives %.0f values per rank (mean; max %.0f)  MatMult %.1f us\n", size,
        received[0] / size, received[1], 1e6 * product);
  if (o.partition_only) return 0;

  Vec v = nullptr;
  GIPSI_PETSC(VecCreateGhost(world, static_cast<PetscInt>(part.num_owned), PETSC_DECIDE,
                             static_cast<PetscInt>(ghosts.size()), ghosts.data(), &v));
  GIPSI_PETSC(VecSet(v, 1.0));
  const double halo = TimePerCall(o, world, [&] {
    VecGhostUpdateBegin(v, INSERT_VALUES, SCATTER_FORWARD);
    VecGhostUpdateEnd(v, INSERT_VALUES, SCATTER_FORWARD);
  });
  GIPSI_PETSC(VecDestroy(&v));
  double one = 1, two[2] = {1, 2}, out[2];
  const double reduce1 =
      TimePerCall(o, world, [&] { MPI_Allreduce(&one, out, 1, MPI_DOUBLE, MPI_SUM, world); });
  const double reduce2 =
      TimePerCall(o, world, [&] { MPI_Allreduce(two, out, 2, MPI_DOUBLE, MPI_SUM, world); });
  if (rank == 0)
    std::printf(
        "ranks %d  halo exchange %.2f us (%.0f ghost values max, %.1f KB)  allreduce 1 double "
        "%.2f us  2 doubles %.2f us\n",
        size, 1e6 * halo, high[1], 8e-3 * high[1], 1e6 * reduce1, 1e6 * reduce2);
  return 0;
}
}  // namespace

int main(int argc, char** argv) { return gipsi::bench::RunBench("comm_bench", argc, argv, Main); }
