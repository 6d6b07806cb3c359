// Strong scaling of the FemSolid split over MPI ranks (parallel/distributed_solid.h): the soft
// cantilever of scenes/cantilever.json (10 × 1 × 1 cm, corotational, E 100 kPa, ν 0.45, density
// 1000, consistent mass, Rayleigh α 2 /s, backward Euler, gravity, the vertices at x = 0 held)
// at any resolution, stepped by 5 ms on every rank of MPI_COMM_WORLD behind a WholeDomainView.
// Prints one line of figures: time per step (median, min and max over the timed steps, each
// ended by a barrier so the slowest rank counts), its split (assembly, linear solves; rank 0's,
// timed steps), Newton and linear iterations and preconditioner set-ups per step, the tip's
// vertical displacement at the end (mean over the nodes at x = L), set-up time (partition +
// assembly) and the first step's time (the preconditioner's first set-up), and the peak
// resident memory per rank (VmHWM) with the bytes per tet it makes.
//
//   mpiexec -np 2 build/release/bench/solid_scaling_bench --cells 80 8 8 --steps 20
//   build/release/bench/solid_scaling_bench --cells 80 8 8 --serial   (the serial FemSolid)
//
// Options: --cells NX NY NZ (hexahedra along the beam; default 80 8 8, 30.7k tets),
// --tets-per-cell 5|6 (default 6, Kuhn's cut; 5: a scene's "tets_per_cell": 5), --steps N
// timed steps (default 20) after --warmup N (default 2), --pc amg|hypre|jacobi|sgs (default
// amg: PETSc's GAMG with the rigid-body modes), --type cg|cholmod (cholmod: MUMPS's LDLᵀ when
// split), --tolerance (CG's, default 1e-6, the serial default), --serial (one rank: the serial
// FemSolid on the whole mesh instead, for the baseline, with CG and block SGS — or --pc
// jacobi — or CHOLMOD with --type cholmod). PETSc options with the prefix solid_ (e.g.
// -solid_ksp_monitor) and -log_view pass through. Run with
// OMP_NUM_THREADS=1 per rank unless measuring threads within ranks.

#include <mpi.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/solid_laws.h"
#include "gipsi/parallel/distributed_solid.h"
#include "gipsi/parallel/parallel_session.h"
#include "gipsi/parallel/whole_domain_view.h"
#include "slab_cli.h"

namespace {

using gipsi::Index;

constexpr double kLength = 0.1, kWidth = 0.01, kHeight = 0.01;  // m (scenes/cantilever.json)

using gipsi::bench::Median;
using gipsi::bench::PeakResidentBytes;

struct Options {
  int nx = 80, ny = 8, nz = 8;
  int steps = 20, warmup = 2;
  std::string pc = "amg";
  std::string type = "cg";
  double tolerance = 1e-6;
  bool serial = false;
  int tets_per_cell = 6;
};

// Exits 2 with CLI11's message on a bad command line (PETSc options such as -log_view pass
// through as extras: PETSc reads them).
Options Parse(int argc, char** argv) {
  Options o;
  std::array<int, 3> cells = {o.nx, o.ny, o.nz};
  CLI::App app{"Strong scaling of the split FemSolid on the cantilever"};
  app.allow_extras();
  app.add_option("--cells", cells, "Hexahedra along the beam")->check(CLI::Range(1, 100000));
  app.add_option("--tets-per-cell", o.tets_per_cell, "Tets per hexahedron (5 or 6)")
      ->check(CLI::IsMember({5, 6}));
  app.add_option("--steps", o.steps, "Timed steps")->check(CLI::Range(1, 100000000));
  app.add_option("--warmup", o.warmup, "Untimed steps first")->check(CLI::NonNegativeNumber);
  app.add_option("--pc", o.pc, "CG's preconditioner")
      ->check(CLI::IsMember({"amg", "hypre", "jacobi", "sgs"}));
  app.add_option("--type", o.type, "Linear solver (cholmod: MUMPS when split)")
      ->check(CLI::IsMember({"cg", "cholmod"}));
  app.add_option("--tolerance", o.tolerance, "CG's relative residual")->check(CLI::PositiveNumber);
  app.add_flag("--serial", o.serial, "The serial FemSolid instead (one rank)");
  gipsi::bench::ParseOrExit(app, argc, argv);
  o.nx = cells[0];
  o.ny = cells[1];
  o.nz = cells[2];
  return o;
}

// scenes/cantilever.json's beam. Newton at its default tolerance (1e-8).
gipsi::FemParams CantileverParams(const Options& o) {
  gipsi::FemParams p;
  p.density = 1000;
  p.material = std::make_shared<gipsi::CorotationalSolid>(1e5, 0.45);
  p.lumped_mass = false;
  p.rayleigh_mass = 2.0;
  p.scheme = gipsi::ImplicitSchemeKind::kBackwardEuler;
  p.linear_solver.type = o.type;
  if (o.type == "cg") p.linear_solver.preconditioner = o.pc;  // direct: the default, unused
  p.linear_solver.tolerance = o.tolerance;
  return p;
}

// The vertices at x = 0 held, on the object's boundary (the whole mesh's, for the view too).
void Clamp(gipsi::SimObject& object) {
  const gipsi::BoundarySurface& b = object.boundary();
  for (Index v = 0; v < b.num_vertices(); ++v)
    if (object.domain().nodes(0, b.vertex_to_node[static_cast<std::size_t>(v)]) <= 1e-12)
      object.boundary_conditions().Fix(v);
}

// The mean vertical displacement of the nodes at x = L. Collective (the view gathers).
double TipDisplacement(const gipsi::SimObject& object, const gipsi::Mesh& whole) {
  const gipsi::FieldId id = object.FindField("displacement");
  Eigen::MatrixXd u(object.field_info(id).components, object.FieldCount(id));
  object.ReadField(id, u);
  double sum = 0;
  int count = 0;
  for (Index n = 0; n < whole.num_nodes(); ++n)
    if (whole.nodes(0, n) >= kLength * (1 - 1e-9)) {
      sum += u(2, n);
      ++count;
    }
  return count > 0 ? sum / count : 0;
}

int Main(int argc, char** argv) {
  const Options o = Parse(argc, argv);
  const MPI_Comm world = gipsi::ParallelSession::world();
  const int rank = gipsi::ParallelSession::rank(world);
  const int size = gipsi::ParallelSession::size(world);
  if (o.serial && size > 1) {
    if (rank == 0) std::fprintf(stderr, "solid_scaling_bench: --serial runs on one rank\n");
    return 2;
  }
  const double t0 = MPI_Wtime();
  const auto whole = std::make_shared<gipsi::Mesh>(gipsi::MakeTetBox(
      gipsi::Vec3::Zero(), gipsi::Vec3(kLength, kWidth, kHeight), {o.nx, o.ny, o.nz},
      o.tets_per_cell == 5 ? gipsi::HexSplit::kFive : gipsi::HexSplit::kSix));
  const double t_mesh = MPI_Wtime() - t0;
  std::unique_ptr<gipsi::SimObject> object;
  const gipsi::FemSolid* solid = nullptr;  // the FemSolid stepped on this rank
  std::string solver;
  if (o.serial) {
    gipsi::FemParams p = CantileverParams(o);
    // The serial default (CG with block SGS) unless Jacobi is asked: GAMG and BoomerAMG are
    // PETSc's.
    if (o.type == "cg" && o.pc != "jacobi") p.linear_solver.preconditioner = "sgs";
    solver = o.type == "cg" ? "serial cg+" + p.linear_solver.preconditioner : "serial cholmod";
    auto s = std::make_unique<gipsi::FemSolid>("beam", whole, std::move(p));
    solid = s.get();
    object = std::move(s);
  } else {
    gipsi::FemParams p = CantileverParams(o);
    auto distribution = std::make_shared<gipsi::DistributedSolid>(whole, world);
    p.distribution = distribution;
    const gipsi::MeshPart& part = distribution->part();
    solver = o.type == "cg" ? "split cg+" + o.pc : "split mumps";
    auto s = std::make_unique<gipsi::FemSolid>("beam", part.mesh, std::move(p));
    solid = s.get();
    object = std::make_unique<gipsi::WholeDomainView>(
        std::move(s), part, whole, world,
        gipsi::WholeDomainView::BoundaryMap{distribution->whole_boundary_vertex(),
                                            distribution->whole_boundary_face()});
  }
  Clamp(*object);
  MPI_Barrier(world);
  const double t_setup = MPI_Wtime() - t0 - t_mesh;
  const double dt = 0.005;
  std::vector<double> times;
  double first_step = 0;
  gipsi::FemProfile before;
  for (int s = 0; s < o.warmup + o.steps; ++s) {
    if (s == o.warmup) before = solid->profile();
    const double start = MPI_Wtime();
    const gipsi::StepStatus status = object->Step(dt);
    MPI_Barrier(world);
    if (!status.ok()) {
      if (rank == 0)
        std::fprintf(stderr, "step %d failed: %s %s\n", s, status.what,
                     object->failure_detail().c_str());
      return 3;
    }
    const double elapsed = MPI_Wtime() - start;
    if (s == 0) first_step = elapsed;
    if (s >= o.warmup) times.push_back(elapsed);
  }
  const gipsi::FemProfile& after = solid->profile();
  const double newton = static_cast<double>(after.newton_iterations - before.newton_iterations);
  const double linear = static_cast<double>(after.linear_iterations - before.linear_iterations);
  const double setups = static_cast<double>(after.factorizations - before.factorizations);
  const double assembly = after.assembly_seconds - before.assembly_seconds;
  const double solve = after.solve_seconds - before.solve_seconds;
  double total = 0;
  for (const double t : times) total += t;
  const double tip = TipDisplacement(*object, *whole);  // collective
  double memory[2] = {PeakResidentBytes(), PeakResidentBytes()};
  MPI_Allreduce(MPI_IN_PLACE, &memory[0], 1, MPI_DOUBLE, MPI_MAX, world);
  MPI_Allreduce(MPI_IN_PLACE, &memory[1], 1, MPI_DOUBLE, MPI_SUM, world);
  if (rank == 0) {
    const double tets = static_cast<double>(whole->num_tets());
    std::printf(
        "ranks %d  tets %.0f  nodes %ld  solver %s  step median %.2f ms (min %.2f, max %.2f)  "
        "split (rank 0) assembly %.1f%% solve %.1f%%  newton/step %.2f  linear/step %.2f  "
        "pc setups/step %.2f  tip uz %.9e m  mesh %.2f s  setup %.2f s  first step %.2f s  "
        "peak RSS/rank %.0f MB (max), %.0f B/tet over all ranks\n",
        size, tets, static_cast<long>(whole->num_nodes()), solver.c_str(), 1e3 * Median(times),
        1e3 * *std::min_element(times.begin(), times.end()),
        1e3 * *std::max_element(times.begin(), times.end()), 100 * assembly / total,
        100 * solve / total, newton / o.steps, linear / o.steps, setups / o.steps, tip, t_mesh,
        t_setup, first_step, memory[0] / 1e6, memory[1] / tets);
  }
  object.reset();  // before PETSc finalises
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  return gipsi::bench::RunBench("solid_scaling_bench", argc, argv, Main);
}
