// A FemSolid made in blocks keeps its part's boundary conditions only (WholeDomainView's store,
// SelectConditionItems), and its checkpoints name the whole boundary's items of the part's: the
// conditions move with the state to another rank count, from a serial run and to one. Each test
// loads the soft cantilever (parallel/cantilever.h) with every kind of condition (a clamp, a
// total force split over the tip's vertices, a pressure on the top's faces, a traction on the
// faces a box selects, a displacement of one node on one axis), runs it 10 steps, checkpoints
// it, and restores it into an object that has only the clamp: the whole boundary's conditions
// after the restore are the written ones bit for bit, and 10 steps on the motion is the
// uninterrupted run's within 1e-9 of the sag (as checkpoint_ranks_test.cc argues). A lost
// condition would show: the loads move the tip by more than 1e-4 of the sag in 10 steps.
// Runs under `mpiexec -np 2` and `-np 4 --oversubscribe`; every test is collective.

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "gipsi/base/state.h"
#include "gipsi/core/row_state.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/geometry/region.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/parallel/distributed_solid.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/whole_domain_view.h"
#include "parallel/cantilever.h"
#include "parallel/checkpoint_files.h"

namespace gipsi {
namespace {

using test::CantileverMesh;
using test::CantileverParams;
using test::FirstRanks;
using test::Folder;
using test::Rank;
using test::Restore;
using test::Size;
using test::World;
using test::Write;

constexpr double kDt = 5e-3;
constexpr int kSteps = 10;

// The items of `object`'s store that `region` selects, and the whole selection's count.
PartitionedObject::ConditionItems Select(const SimObject& object, const Region& region,
                                         bool faces) {
  if (const auto* split = dynamic_cast<const PartitionedObject*>(&object))
    if (!split->holds_whole_domain()) return split->SelectConditionItems(region, faces);
  PartitionedObject::ConditionItems out;
  out.items = faces ? SelectBoundaryFaces(region, object.domain(), object.boundary())
                    : SelectBoundaryVertices(region, object.domain(), object.boundary());
  out.whole_count = static_cast<std::int64_t>(out.items.size());
  return out;
}

// The clamp at x = 0 and, when `loaded`, the other conditions.
void Apply(SimObject& object, bool loaded) {
  BoundaryConditions& bcs = object.boundary_conditions();
  for (const int v : Select(object, GroupRegion{"xmin"}, false).items) bcs.Fix(v);
  if (!loaded) return;
  const PartitionedObject::ConditionItems tip = Select(object, GroupRegion{"xmax"}, false);
  ASSERT_GT(tip.whole_count, 0);
  for (const int v : tip.items)
    bcs.SetForce(v, Vec3(0, 0.002, -0.01) / static_cast<double>(tip.whole_count));
  for (const int f : Select(object, GroupRegion{"zmax"}, true).items) bcs.SetPressure(f, 50);
  for (const int f :
       Select(object, BoxRegion{Vec3(0.03, -1, -1), Vec3(0.07, 0.0001, 1)}, true).items)
    bcs.SetTraction(f, Vec3(0, 0, -20));
  for (const int v : Select(object, NodeIdsRegion{{20}}, false).items)
    bcs.PrescribeDisplacement(v, Vec3(0, 0, -0.002), 4);
}

// The cantilever made in blocks over `comm` (no rank holds its mesh), its FemSolid's view
// keeping its part's conditions.
struct BlocksBeam {
  std::shared_ptr<DistributedSolid> distribution;
  std::unique_ptr<WholeDomainView> view;
  BlocksBeam(MPI_Comm comm, bool loaded) {
    distribution = std::make_shared<DistributedSolid>(
        PartitionMeshBlocks(MakeTetBoxBlock(Vec3::Zero(), Vec3(0.1, 0.01, 0.01), {20, 2, 2},
                                            HexSplit::kSix, Rank(comm), Size(comm)),
                            comm),
        comm);
    FemParams params = CantileverParams("amg");
    params.distribution = distribution;
    const MeshPart& part = distribution->part();
    view = std::make_unique<WholeDomainView>(
        std::make_unique<FemSolid>("beam", part.mesh, std::move(params)), part, comm,
        WholeDomainView::BoundaryMap{
            distribution->whole_boundary_vertex(), distribution->whole_boundary_face(),
            distribution->whole_boundary_vertices(), distribution->whole_boundary_faces()});
    Apply(*view, loaded);
  }
  void Run() const {
    for (int s = 0; s < kSteps; ++s) ASSERT_TRUE(view->Step(kDt).ok());
  }
};

// The whole boundary's applied conditions, vertex rows then face rows: a serial object's, or
// (`solid` given: its view's part) gathered on every rank of the solid's communicator, each
// owned vertex and each face from its part.
std::vector<double> Table(const SimObject& object, const DistributedSolid* solid = nullptr) {
  using Applied = BoundaryConditions::Applied;
  constexpr Index kVertexRow = Applied::kVertexRow, kFaceRow = Applied::kFaceRow;
  const Applied& applied = object.boundary_conditions().applied();
  const Index vertices = solid != nullptr ? static_cast<Index>(solid->whole_boundary_vertices())
                                          : applied.value.cols();
  const Index faces = solid != nullptr ? static_cast<Index>(solid->whole_boundary_faces())
                                       : applied.pressure.size();
  std::vector<double> table(static_cast<std::size_t>(vertices * kVertexRow + faces * kFaceRow));
  auto vertex_row = [&table](Index v) { return table.data() + v * kVertexRow; };
  auto face_row = [&table, vertices](Index f) {
    return table.data() + vertices * kVertexRow + f * kFaceRow;
  };
  if (solid == nullptr) {
    for (Index v = 0; v < vertices; ++v) applied.VertexRow(v, vertex_row(v));
    for (Index f = 0; f < faces; ++f) applied.FaceRow(f, face_row(f));
    return table;
  }
  const std::vector<int>& v2n = object.boundary().vertex_to_node;
  for (std::size_t v = 0; v < v2n.size(); ++v)
    if (v2n[v] < solid->part().num_owned)
      applied.VertexRow(static_cast<Index>(v), vertex_row(solid->whole_boundary_vertex()[v]));
  for (std::size_t f = 0; f < solid->whole_boundary_face().size(); ++f)
    applied.FaceRow(static_cast<Index>(f), face_row(solid->whole_boundary_face()[f]));
  MPI_Allreduce(MPI_IN_PLACE, table.data(), static_cast<int>(table.size()), MPI_DOUBLE, MPI_SUM,
                solid->comm());
  return table;
}

// Every node's displacement (a part-only view's gathered from the nodes' owners).
Eigen::MatrixXd Displacement(const SimObject& object) {
  const FieldId id = object.FindField("displacement");
  if (const auto* view = dynamic_cast<const WholeDomainView*>(&object)) {
    std::vector<int> nodes(static_cast<std::size_t>(view->whole_num_nodes()));
    for (std::size_t i = 0; i < nodes.size(); ++i) nodes[i] = static_cast<int>(i);
    Eigen::MatrixXd out(3, static_cast<Index>(nodes.size()));
    view->ReadWholeNodes(id, nodes, out);
    return out;
  }
  Eigen::MatrixXd out(3, object.domain().num_nodes());
  object.ReadField(id, out);
  return out;
}

void ExpectSameBits(const std::vector<double>& restored, const std::vector<double>& written,
                    const std::string& label) {
  ASSERT_EQ(restored.size(), written.size()) << label;
  for (std::size_t i = 0; i < written.size(); ++i)
    ASSERT_EQ(std::bit_cast<std::uint64_t>(restored[i]), std::bit_cast<std::uint64_t>(written[i]))
        << label << ": value " << i;
}

// The motion 10 steps after the restore against the uninterrupted run's, and what the loads
// did in those steps (so that a lost condition would show).
void ExpectSwingsOn(const Eigen::MatrixXd& continued, const Eigen::MatrixXd& reference,
                    const Eigen::MatrixXd& at_checkpoint, const std::string& label) {
  const double sag = -reference.row(2).minCoeff();
  EXPECT_GT(sag, 0.001) << label;
  EXPECT_GT((reference - at_checkpoint).cwiseAbs().maxCoeff(), 1e-4 * sag) << label;
  const double worst = (continued - reference).cwiseAbs().maxCoeff();
  EXPECT_LE(worst, 1e-9 * sag) << label;
  std::printf("[ %s ] sag %.4g m; largest difference %.3g m\n", label.c_str(), sag, worst);
}

TEST(CheckpointConditions, APartsConditionsMoveToAnotherRankCount) {
  const int world = Size(World());
  for (const auto& [from, to] : {std::pair{world / 2, world}, std::pair{world, world - 1}}) {
    const std::string label = fmt::format("conditions {} to {} ranks", from, to);
    const std::filesystem::path folder = Folder(fmt::format("conditions{}to{}", from, to));
    std::vector<double> written;
    Eigen::MatrixXd at_checkpoint, reference;
    {
      const FirstRanks writers(from);
      if (writers.member()) {
        const BlocksBeam beam(writers.comm(), true);
        beam.Run();
        (void)Write(*beam.view, writers.comm(), folder);
        written = Table(*beam.view, beam.distribution.get());
        at_checkpoint = Displacement(*beam.view);
        beam.Run();
        reference = Displacement(*beam.view);
      }
    }
    std::vector<std::filesystem::path> files;
    for (int r = 0; r < from; ++r) files.push_back(folder / fmt::format("p{}", r));
    const FirstRanks readers(to);
    if (readers.member()) {
      const BlocksBeam beam(readers.comm(), false);
      EXPECT_NE(Table(*beam.view, beam.distribution.get()),
                written);  // only the clamp before the restore
      Restore(*beam.view, readers.comm(), files);
      const std::vector<double> restored = Table(*beam.view, beam.distribution.get());
      beam.Run();
      const Eigen::MatrixXd continued = Displacement(*beam.view);
      if (Rank(World()) == 0) {
        ExpectSameBits(restored, written, label);
        ExpectSwingsOn(continued, reference, at_checkpoint, label);
      }
    }
    MPI_Barrier(World());
    if (Rank(World()) == 0) std::filesystem::remove_all(folder);
  }
}

TEST(CheckpointConditions, ConditionsMoveBetweenSerialAndSplitRuns) {
  const std::filesystem::path folder = Folder("conditions_serial");
  // A serial run's checkpoint restored on every rank of the world.
  std::vector<double> written;
  Eigen::MatrixXd at_checkpoint, reference;
  if (Rank(World()) == 0) {
    FemSolid beam("beam", CantileverMesh(), CantileverParams());
    Apply(beam, true);
    for (int s = 0; s < kSteps; ++s) ASSERT_TRUE(beam.Step(kDt).ok());
    StateWriter out;
    beam.SaveState(out);
    WriteCheckpointFile(folder / "serial.gck", out.bytes());
    written = Table(beam);
    at_checkpoint = Displacement(beam);
    for (int s = 0; s < kSteps; ++s) ASSERT_TRUE(beam.Step(kDt).ok());
    reference = Displacement(beam);
  }
  MPI_Barrier(World());
  {
    const BlocksBeam beam(World(), false);
    Restore(*beam.view, World(), {folder / "serial.gck"});
    const std::vector<double> restored = Table(*beam.view, beam.distribution.get());
    beam.Run();
    const Eigen::MatrixXd continued = Displacement(*beam.view);
    if (Rank(World()) == 0) {
      const std::string label = fmt::format("serial conditions to {} ranks", Size(World()));
      ExpectSameBits(restored, written, label);
      ExpectSwingsOn(continued, reference, at_checkpoint, label);
    }
  }
  // A distributed run's checkpoint (every rank's file) read on one process.
  std::vector<std::filesystem::path> files;
  {
    const BlocksBeam beam(World(), true);
    beam.Run();
    files = Write(*beam.view, World(), folder);
    written = Table(*beam.view, beam.distribution.get());
    at_checkpoint = Displacement(*beam.view);
    beam.Run();
    reference = Displacement(*beam.view);
  }
  MPI_Barrier(World());
  if (Rank(World()) == 0) {
    FemSolid beam("beam", CantileverMesh(), CantileverParams());
    Apply(beam, false);
    SetCheckpointPieces(files);
    StateReader in(ReadCheckpointFile(files[0]), files[0].string());
    beam.RestoreState(in);
    SetCheckpointPieces({});
    const std::vector<double> restored = Table(beam);
    for (int s = 0; s < kSteps; ++s) ASSERT_TRUE(beam.Step(kDt).ok());
    const std::string label = fmt::format("{} ranks' conditions on one process", Size(World()));
    ExpectSameBits(restored, written, label);
    ExpectSwingsOn(Displacement(beam), reference, at_checkpoint, label);
  }
  MPI_Barrier(World());
  if (Rank(World()) == 0) std::filesystem::remove_all(folder);
}

}  // namespace
}  // namespace gipsi
