// A barycentric (or nearest-item) copy between objects split differently (docs/scale-out.md): the
// N-version slab's monodomain, made in blocks, read at the nodes of a coarser mesh of the slab made
// in blocks too (the bioelectricity on a fine mesh, the mechanics on a coarse one). Times, per
// firing, the parts answering for each rank's points (PartitionedObject::InterpolateAtPoints,
// or NearestAtPoints with --mapping nearest: what a FieldCopy does now) against the whole-field
// path it replaces, run in the same process on the same slab: the split object's view gathers V
// whole on every rank (MPI_Allgatherv) and each rank interpolates its points in the whole mesh (or
// takes their nearest nodes). Also the set-up of each (the parts locating the points, against a
// point map built on the whole mesh). Medians of batches, each batch timed on every rank and its
// slowest rank counted.
//
//   mpiexec -np 2 build/release/bench/coupling_bench --cells 100 35 15 --target-cells 20 7 3
//   build/release/bench/coupling_bench --cells 100 35 15 --target-cells 20 7 3
//
// Options: --cells NX NY NZ (the fine slab's hexahedra, 6 tets each; default 100 35 15: 0.2 mm),
// --target-cells NX NY NZ (the coarse slab's; default 20 7 3: 1 mm), --mapping
// barycentric|nearest (default barycentric), --batches N (default 15) of --reps N (default 20)
// firings each.

#include <mpi.h>

#include <array>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gipsi/geometry/mesh_block.h"
#include "gipsi/models/ep/phenomenological.h"
#include "gipsi/parallel/distributed_monodomain.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/whole_domain_view.h"
#include "slab_cli.h"

namespace {

struct Options {
  std::array<int, 3> cells = {100, 35, 15}, target = {20, 7, 3};
  int batches = 15, reps = 20;
  std::string mapping = "barycentric";
};

Options Parse(int argc, char** argv) {
  Options o;
  CLI::App app{"A barycentric copy between objects split differently"};
  gipsi::bench::AddSlabCells(app, o.cells);
  app.add_option("--target-cells", o.target, "Hexahedra along the coarse slab (6 tets each)")
      ->check(CLI::Range(1, 100000));
  app.add_option("--mapping", o.mapping, "The copy's mapping")
      ->check(CLI::IsMember({"barycentric", "nearest"}));
  app.add_option("--batches", o.batches, "Timed batches")->check(CLI::Range(1, 100000000));
  app.add_option("--reps", o.reps, "Firings per batch")->check(CLI::Range(1, 100000000));
  gipsi::bench::ParseOrExit(app, argc, argv);
  return o;
}

gipsi::EpTissueParams Tissue() {
  gipsi::EpTissueParams p;
  p.cell = std::make_shared<gipsi::AlievPanfilov>();
  p.fibre = gipsi::Vec3::UnitX();
  return p;
}

int Main(int argc, char** argv) {
  const Options o = Parse(argc, argv);
  const MPI_Comm world = gipsi::ParallelSession::world();
  const int rank = gipsi::ParallelSession::rank(world);
  const int size = gipsi::ParallelSession::size(world);
  auto block = [&](const std::array<int, 3>& cells) {
    return gipsi::PartitionMeshBlocks(
        gipsi::MakeTetBoxBlock(gipsi::Vec3::Zero(), gipsi::bench::kSlabSize, cells,
                               gipsi::HexSplit::kSix, rank, size),
        world);
  };
  // The fine tissue made in blocks, its V a linear field; the coarse mesh's part: its nodes are
  // this rank's points.
  auto part = std::make_unique<gipsi::DistributedMonodomain>("ep", block(o.cells), Tissue(), world);
  const gipsi::MeshPart& fine = part->part();
  gipsi::WholeDomainView tissue(std::move(part), fine, world);
  const gipsi::FieldId v = tissue.FindField("V");
  {
    Eigen::MatrixXd values = 1e3 * fine.mesh->nodes.colwise().sum();
    tissue.local_part().WriteField(tissue.local_part().FindField("V"), values);
  }
  const gipsi::MeshPart coarse = block(o.target);
  const gipsi::Points& points = coarse.mesh->nodes;
  Eigen::MatrixXd at(1, points.cols());

  std::unique_ptr<gipsi::PartsInterpolation> parts;
  const bool nearest = o.mapping == "nearest";
  const double parts_setup = gipsi::bench::TimeOnce(world, [&] {
    parts = nearest ? tissue.NearestAtPoints(gipsi::FieldLocation::kNode, points)
                    : tissue.InterpolateAtPoints(points);
  });
  const double parts_fire = gipsi::bench::SlowestRankPerCall(
      world, o.batches, o.reps, [&] { parts->Interpolate(v, at, std::nullopt); });

  // The whole-field path, on the same slab: a view holding the whole mesh.
  const auto whole = std::make_shared<const gipsi::Mesh>(
      gipsi::bench::SlabMesh(o.cells[0], o.cells[1], o.cells[2]));
  auto whole_part = std::make_unique<gipsi::DistributedMonodomain>("ep", *whole, Tissue(), world);
  const gipsi::MeshPart& same = whole_part->part();
  gipsi::WholeDomainView viewed(std::move(whole_part), same, whole, world);
  {
    Eigen::MatrixXd values = 1e3 * same.mesh->nodes.colwise().sum();
    viewed.local_part().WriteField(viewed.local_part().FindField("V"), values);
  }
  Eigen::MatrixXd gathered(1, whole->num_nodes()), at_whole(1, points.cols());
  gipsi::PointMap map;
  const double whole_setup = gipsi::bench::TimeOnce(world, [&] {
    map = nearest ? gipsi::PointMap::Nearest(whole->nodes, points) : viewed.MapFromNodes(points);
  });
  const double whole_fire = gipsi::bench::SlowestRankPerCall(world, o.batches, o.reps, [&] {
    viewed.ReadField(v, gathered);
    map.Apply(gathered, at_whole);
  });
  double differ = (at - at_whole).cwiseAbs().maxCoeff();
  MPI_Allreduce(MPI_IN_PLACE, &differ, 1, MPI_DOUBLE, MPI_MAX, world);
  long long counts[2] = {static_cast<long long>(points.cols()), 0};
  MPI_Allreduce(MPI_IN_PLACE, counts, 1, MPI_LONG_LONG, MPI_SUM, world);
  if (rank == 0)
    std::printf(
        "%s: ranks %d  source %lld tets %lld nodes  target points %lld (all ranks)\n"
        "set-up: parts %.3g ms  whole mesh %.3g ms\n"
        "firing: parts %.3g ms  whole field %.3g ms  ratio %.3g  (values differ by %.2g)\n",
        o.mapping.c_str(), size, static_cast<long long>(whole->num_tets()),
        static_cast<long long>(whole->num_nodes()), counts[0], 1e3 * parts_setup, 1e3 * whole_setup,
        1e3 * parts_fire, 1e3 * whole_fire, whole_fire / parts_fire, differ);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return gipsi::bench::RunBench("coupling_bench", argc, argv, Main);
}
