// The transmural fibre rule's set-up (models/fibres/rule_based_fibres.h): the serial rule
// (CHOLMOD on the whole mesh, what every rank did before the rule was split) against the rule
// solved over the ranks (parallel/distributed_fibres.h: CG + Jacobi, each rank its part). On
// the heart scene's left ventricle (scenes/heart.json) meshed by Gmsh at --size; the mesh and
// its cut are made first and not timed. Prints the median, min and max of --repeat calls, each
// ended by a barrier so that the slowest rank counts, and the mesh's size.
//
//   build/release/bench/fibre_rule_bench --size 1.5 --serial    (the serial rule, one process)
//   mpiexec -np 2 build/release/bench/fibre_rule_bench --size 1.5
//
// Run with OMP_NUM_THREADS=1 per rank (CHOLMOD's BLAS is threaded otherwise).

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "gipsi/geometry/generators.h"
#include "gipsi/parallel/distributed_fibres.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/parallel_session.h"
#include "slab_cli.h"

namespace {

struct Options {
  double size_mm = 1.5;
  int repeat = 5;
  bool serial = false;
};

int Main(int argc, char** argv) {
  Options o;
  CLI::App app{"Set-up of the transmural fibre rule, serial and over the ranks"};
  app.allow_extras();  // PETSc options (-fibres_ksp_monitor) pass through
  app.add_option("--size", o.size_mm, "Gmsh's element size [mm]")->check(CLI::Range(0.2, 20.0));
  app.add_option("--repeat", o.repeat, "Timed calls")->check(CLI::Range(1, 1000));
  app.add_flag("--serial", o.serial, "The serial rule on the whole mesh (one process)");
  gipsi::bench::ParseOrExit(app, argc, argv);
  const MPI_Comm world = gipsi::ParallelSession::world();
  const int rank = gipsi::ParallelSession::rank(world);
  const int size = gipsi::ParallelSession::size(world);
  if (o.serial && size != 1) throw std::runtime_error("--serial runs on one process");

  gipsi::EllipsoidShellSpec spec;  // scenes/heart.json's left ventricle
  spec.endo_short = 0.022;
  spec.endo_long = 0.048;
  spec.epi_short = 0.032;
  spec.epi_long = 0.058;
  spec.base_z = 0.012;
  spec.mesh_size = 1e-3 * o.size_mm;
  const gipsi::Mesh whole = gipsi::MakeEllipsoidShell(spec);
  gipsi::TransmuralFibreRule rule;
  rule.endo = gipsi::GroupRegion{"endo"};
  rule.epi = gipsi::GroupRegion{"epi"};
  const gipsi::MeshPart part = gipsi::PartitionMesh(whole, world);

  std::vector<double> times;
  for (int k = 0; k < o.repeat; ++k) {
    MPI_Barrier(world);
    const auto start = std::chrono::steady_clock::now();
    const gipsi::FibreField fibres = o.serial ? gipsi::MakeTransmuralFibres(whole, rule)
                                              : gipsi::TransmuralFibresOnPart(part, rule, world);
    MPI_Barrier(world);
    times.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (fibres.fibre.cols() != part.mesh->num_tets() && !o.serial)
      throw std::runtime_error("the split rule gave a fibre per tet of another mesh");
  }
  if (rank == 0)
    std::printf(
        "%s  ranks %d  tets %ld  nodes %ld  fibre rule median %.3f s (min %.3f, max %.3f)  "
        "peak memory %.0f MB (rank 0)\n",
        o.serial ? "serial (CHOLMOD)" : "split (CG + Jacobi)", size,
        static_cast<long>(whole.num_tets()), static_cast<long>(whole.num_nodes()),
        gipsi::bench::Median(times), *std::min_element(times.begin(), times.end()),
        *std::max_element(times.begin(), times.end()), gipsi::bench::PeakResidentBytes() / 1e6);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return gipsi::bench::RunBench("fibre_rule_bench", argc, argv, Main);
}
