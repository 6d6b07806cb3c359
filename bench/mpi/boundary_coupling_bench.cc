// A BoundaryCoupling between two solids split over the ranks (docs/scale-out.md): a soft bar
// (the driver) with a slab glued on its top face (the follower), meshed apart on grids that do
// not match. Times a firing (the driver's displacement interpolated at the follower's interface
// vertices, prescribed there, and the follower's reactions spread back onto the driver) with
// both made in blocks, each rank its part of the interface (PartitionedObject::
// InterpolateOnBoundary: what a scene run does now), against the path it replaces, run in the
// same process on the same meshes: views holding the whole meshes, whose boundary fields are
// gathered whole on every rank at each firing. Also the connector's set-up in each. Medians of
// batches, each batch timed on every rank and its slowest rank counted. Both are fired after
// one step of 5 ms under gravity, so the reactions are not zero; the total force the driver
// receives is compared. Also the time to read the follower's reactions alone (an assembly of
// its internal forces, the same work in both: the rest is the coupling's own).
//
//   mpiexec -np 2 build/release/bench/boundary_coupling_bench --cells 60 12 12 --top-cells 50 10 2
//   build/release/bench/boundary_coupling_bench
//
// Options: --cells NX NY NZ (the 12 × 2.4 × 2.4 cm bar's hexahedra, 6 tets each; default
// 60 12 12), --top-cells NX NY NZ (the 12 × 2.4 × 0.6 cm slab's; default 50 10 2), --batches N
// (default 15) of --reps N (default 20) firings each.

#include <mpi.h>

#include <array>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "gipsi/geometry/mesh_block.h"
#include "gipsi/models/connectors/boundary_coupling.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/solid_laws.h"
#include "gipsi/parallel/distributed_solid.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/whole_domain_view.h"
#include "slab_cli.h"

namespace {

using gipsi::Vec3;

struct Options {
  std::array<int, 3> cells = {60, 12, 12}, top = {50, 10, 2};
  int batches = 15, reps = 20;
};

Options Parse(int argc, char** argv) {
  Options o;
  CLI::App app{"A boundary coupling between solids split over the ranks"};
  app.add_option("--cells", o.cells, "Hexahedra along the bar (6 tets each)")
      ->check(CLI::Range(1, 100000));
  app.add_option("--top-cells", o.top, "Hexahedra along the slab on its top (6 tets each)")
      ->check(CLI::Range(1, 100000));
  app.add_option("--batches", o.batches, "Timed batches")->check(CLI::Range(1, 100000000));
  app.add_option("--reps", o.reps, "Firings per batch")->check(CLI::Range(1, 100000000));
  gipsi::bench::ParseOrExit(app, argc, argv);
  return o;
}

struct Box {
  Vec3 lo, hi;
  std::array<int, 3> cells;
};

gipsi::FemParams Params() {
  gipsi::FemParams p;
  p.material = std::make_shared<gipsi::CorotationalSolid>(1e5, 0.45);
  p.rayleigh_mass = 2.0;
  p.scheme = gipsi::ImplicitSchemeKind::kBackwardEuler;
  return p;
}

// A piece made in blocks (a view without its whole mesh), or cut from the whole mesh (a view
// holding it: the path scene runs took for a BoundaryCoupling's objects before).
std::unique_ptr<gipsi::WholeDomainView> Piece(const std::string& name, const Box& box,
                                              bool in_blocks, MPI_Comm world) {
  gipsi::FemParams p = Params();
  std::shared_ptr<gipsi::DistributedSolid> distribution;
  std::shared_ptr<const gipsi::Mesh> whole;
  if (in_blocks) {
    distribution = std::make_shared<gipsi::DistributedSolid>(
        gipsi::PartitionMeshBlocks(
            gipsi::MakeTetBoxBlock(box.lo, box.hi, box.cells, gipsi::HexSplit::kSix,
                                   gipsi::ParallelSession::rank(world),
                                   gipsi::ParallelSession::size(world)),
            world),
        world);
  } else {
    whole = std::make_shared<gipsi::Mesh>(gipsi::MakeTetBox(box.lo, box.hi, box.cells));
    distribution = std::make_shared<gipsi::DistributedSolid>(whole, world);
  }
  p.distribution = distribution;
  const gipsi::MeshPart& part = distribution->part();
  auto solid = std::make_unique<gipsi::FemSolid>(name, part.mesh, std::move(p));
  std::unique_ptr<gipsi::WholeDomainView> view =
      in_blocks
          ? std::make_unique<gipsi::WholeDomainView>(
                std::move(solid), part, world,
                gipsi::WholeDomainView::BoundaryMap{
                    distribution->whole_boundary_vertex(), distribution->whole_boundary_face(),
                    distribution->whole_boundary_vertices(), distribution->whole_boundary_faces()})
          : std::make_unique<gipsi::WholeDomainView>(
                std::move(solid), part, whole, world,
                gipsi::WholeDomainView::BoundaryMap{distribution->whole_boundary_vertex(),
                                                    distribution->whole_boundary_face()});
  if (box.lo.z() == 0) {  // the bar: clamped at x = 0
    const gipsi::BoundarySurface& b = view->boundary();
    for (gipsi::Index v = 0; v < b.num_vertices(); ++v)
      if (view->domain().nodes(0, b.vertex_to_node[static_cast<std::size_t>(v)]) == 0)
        view->boundary_conditions().Fix(v);
  }
  return view;
}

struct Timed {
  double setup = 0, fire = 0, reaction = 0;
  Vec3 force = Vec3::Zero();  // the total force the driver receives at a firing
  long long interface = 0;    // interface vertices
};

Timed Measure(const Options& o, bool in_blocks, MPI_Comm world) {
  const Box bar{Vec3::Zero(), Vec3(0.12, 0.024, 0.024), o.cells};
  const Box top{Vec3(0, 0, 0.024), Vec3(0.12, 0.024, 0.030), o.top};
  std::unique_ptr<gipsi::WholeDomainView> driver = Piece("bar", bar, in_blocks, world);
  std::unique_ptr<gipsi::WholeDomainView> follower = Piece("top", top, in_blocks, world);
  Timed out;
  std::unique_ptr<gipsi::BoundaryCoupling> glue;
  out.setup = gipsi::bench::TimeOnce(world, [&] {
    glue = std::make_unique<gipsi::BoundaryCoupling>("glue", *driver, *follower, std::nullopt, -1);
  });
  // Interface vertices counted once: on a part by its node's owner, whole on rank 0.
  for (const int v : glue->interface_vertices())
    if (in_blocks ? follower->boundary().vertex_to_node[static_cast<std::size_t>(v)] <
                        follower->num_owned_nodes()
                  : gipsi::ParallelSession::rank(world) == 0)
      ++out.interface;
  MPI_Allreduce(MPI_IN_PLACE, &out.interface, 1, MPI_LONG_LONG, MPI_SUM, world);
  if (!glue->Fire(0).ok() || !driver->Step(0.005).ok() || !follower->Step(0.005).ok())
    throw std::runtime_error("the glued bar's first step failed");
  out.fire = gipsi::bench::SlowestRankPerCall(world, o.batches, o.reps, [&] {
    if (!glue->Fire(0.005).ok()) throw std::runtime_error("a firing failed");
  });
  // The part of a firing that is the follower's own work: its reaction forces evaluated (an
  // assembly of its internal forces over its part), read as the connector reads them.
  const gipsi::FieldId reaction = follower->FindField("reaction_force");
  Eigen::MatrixXd r(3, follower->FieldCount(reaction));
  out.reaction = gipsi::bench::SlowestRankPerCall(world, o.batches, o.reps,
                                                  [&] { follower->ReadField(reaction, r); });
  driver->BeginMacroStep();
  if (!glue->Fire(0.005).ok()) throw std::runtime_error("a firing failed");
  const gipsi::BoundaryConditions& bc = driver->boundary_conditions();
  const gipsi::BoundarySurface& b = driver->boundary();
  for (gipsi::Index v = 0; v < b.num_vertices(); ++v)
    if (!in_blocks || b.vertex_to_node[static_cast<std::size_t>(v)] < driver->num_owned_nodes())
      out.force += bc.force(v) - bc.applied().force.col(v);
  if (in_blocks) MPI_Allreduce(MPI_IN_PLACE, out.force.data(), 3, MPI_DOUBLE, MPI_SUM, world);
  return out;
}

int Main(int argc, char** argv) {
  const Options o = Parse(argc, argv);
  const MPI_Comm world = gipsi::ParallelSession::world();
  const int rank = gipsi::ParallelSession::rank(world);
  const int size = gipsi::ParallelSession::size(world);
  const Timed parts = Measure(o, true, world);
  const Timed whole = Measure(o, false, world);
  if (rank == 0)
    std::printf(
        "ranks %d  bar %d x %d x %d cells  slab on top %d x %d x %d cells  interface vertices "
        "%lld (%lld whole)\n"
        "set-up: parts %.3g ms  whole meshes %.3g ms\n"
        "firing: parts %.3g ms  whole fields %.3g ms  ratio %.3g\n"
        "  of which the follower's reactions read: parts %.3g ms  whole fields %.3g ms\n"
        "force on the bar: parts (%.6g, %.6g, %.6g) N  whole (%.6g, %.6g, %.6g) N  differ by "
        "%.2g\n",
        size, o.cells[0], o.cells[1], o.cells[2], o.top[0], o.top[1], o.top[2], parts.interface,
        whole.interface, 1e3 * parts.setup, 1e3 * whole.setup, 1e3 * parts.fire, 1e3 * whole.fire,
        whole.fire / parts.fire, 1e3 * parts.reaction, 1e3 * whole.reaction, parts.force.x(),
        parts.force.y(), parts.force.z(), whole.force.x(), whole.force.y(), whole.force.z(),
        (parts.force - whole.force).norm());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return gipsi::bench::RunBench("boundary_coupling_bench", argc, argv, Main);
}
