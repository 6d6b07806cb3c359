// A split object's checkpoint (a monodomain's, a solid's) restored on another rank count
// (WholeDomainView, RowState, MoveRows): written by the first N ranks of MPI_COMM_WORLD, restored
// by the first M. Runs under `mpiexec -np 2` and `-np 4 --oversubscribe`; every test is collective.

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/core/row_state.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/geometry/region.h"
#include "gipsi/models/ep/monodomain.h"
#include "gipsi/models/ep/ten_tusscher_panfilov_2006.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/solid_laws.h"
#include "gipsi/parallel/distributed_monodomain.h"
#include "gipsi/parallel/distributed_solid.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/parallel_session.h"
#include "gipsi/parallel/whole_domain_view.h"
#include "parallel/cantilever.h"
#include "parallel/checkpoint_files.h"

namespace gipsi {
namespace {

using test::CantileverMesh;
using test::CantileverParams;
using test::Clamp;
using test::FirstRanks;
using test::Folder;
using test::Rank;
using test::Restore;
using test::Size;
using test::World;
using test::Write;

// The N-version benchmark slab (scenes/slab_ep_0.5mm.json: 0.5 mm; coarser meshes block the front),
// its solver at 1e-11 (see distributed_monodomain_test.cc), stimulated at the corner.
EpTissueParams SlabParams() {
  EpTissueParams p;
  p.cell = std::make_shared<TenTusscherPanfilov2006>();
  p.sigma_longitudinal = 0.17 * 0.62 / (0.17 + 0.62);
  p.sigma_transverse = 0.019 * 0.24 / (0.019 + 0.24);
  p.fibre = Vec3::UnitX();
  p.linear.preconditioner = "jacobi";
  p.linear.tolerance = 1e-11;
  StimulusSpec corner;
  corner.name = "corner";
  corner.region = BoxRegion{Vec3::Constant(-1e-6), Vec3::Constant(0.0015001)};
  corner.amplitude = 50000.0 / 1400.0;
  corner.pulses.duration = 2.0;
  p.stimuli.push_back(corner);
  return p;
}

const Vec3 kSize(0.020, 0.007, 0.003);
constexpr double kDt = 1e-5;  // s

// The slab split over `comm`: part-only (made in blocks) or with the whole mesh on every rank.
struct SplitSlab {
  std::shared_ptr<const Mesh> whole;
  std::unique_ptr<WholeDomainView> view;
  DistributedMonodomain* tissue = nullptr;
  SplitSlab(MPI_Comm comm, bool part_only, std::array<int, 3> cells = {40, 14, 6}) {
    std::unique_ptr<DistributedMonodomain> part;
    if (part_only) {
      part = std::make_unique<DistributedMonodomain>(
          "slab",
          PartitionMeshBlocks(
              MakeTetBoxBlock(Vec3::Zero(), kSize, cells, HexSplit::kSix, Rank(comm), Size(comm)),
              comm),
          SlabParams(), comm);
    } else {
      whole = std::make_shared<Mesh>(MakeTetBox(Vec3::Zero(), kSize, cells));
      part = std::make_unique<DistributedMonodomain>("slab", *whole, SlabParams(), comm);
    }
    tissue = part.get();
    const MeshPart& mesh_part = tissue->part();
    view = part_only ? std::make_unique<WholeDomainView>(std::move(part), mesh_part, comm)
                     : std::make_unique<WholeDomainView>(std::move(part), mesh_part, whole, comm);
  }
  void Run(long steps) const {
    for (long s = 0; s < steps; ++s) ASSERT_TRUE(view->Step(kDt).ok());
  }
  // The state's rows of every node, whole-mesh order, on rank 0 of the object's ranks.
  [[nodiscard]] std::vector<double> Rows() const {
    const int width = EpState::RowWidth(tissue->cell());
    const std::vector<double> local = tissue->state().ToRows();
    std::vector<double> all;
    for (int j = 0; j < width; ++j) {
      std::vector<double> column(static_cast<std::size_t>(tissue->num_nodes()));
      for (std::size_t i = 0; i < column.size(); ++i)
        column[i] = local[i * static_cast<std::size_t>(width) + static_cast<std::size_t>(j)];
      const std::vector<double> gathered = tissue->Gather(column.data());
      all.insert(all.end(), gathered.begin(), gathered.end());
    }
    return all;  // column after column
  }
};

struct Move {
  int from, to;
  bool part_only;
};

// Checkpointed at 10 ms on N ranks and restored on M: the restored state is the written one,
// bit for bit, at every node; run on to 30 ms (the front has since reached several times as
// many nodes, across the cuts of both partitions),
// the activation times and voltages agree with the uninterrupted run on N within what the
// solver's tolerance allows (1e-5 ms, as distributed_monodomain_test.cc argues; 1e-2 mV: the
// steepest upstroke, ~300 mV/ms, over that shift), not bitwise: the other cut sums in another
// order.
void MovesAndRunsOn(const Move& move, const std::string& label) {
  const std::filesystem::path folder = Folder(label);
  const long before = 1000, after = 2000;
  std::vector<std::filesystem::path> files;
  std::vector<double> written, reference;
  {
    const FirstRanks writers(move.from);
    if (writers.member()) {
      const SplitSlab slab(writers.comm(), move.part_only);
      slab.Run(before);
      files = Write(*slab.view, writers.comm(), folder);
      written = slab.Rows();
      slab.Run(after);
      reference = slab.Rows();
    }
  }
  int count = static_cast<int>(files.size());
  MPI_Bcast(&count, 1, MPI_INT, 0, World());
  files.clear();
  for (int r = 0; r < count; ++r) files.push_back(folder / fmt::format("p{}", r));
  const FirstRanks readers(move.to);
  if (readers.member()) {
    const SplitSlab slab(readers.comm(), move.part_only);
    Restore(*slab.view, readers.comm(), files);
    EXPECT_NEAR(slab.view->time(), before * kDt, 1e-15);
    EXPECT_EQ(slab.tissue->step_count(), before);
    const std::vector<double> restored = slab.Rows();
    slab.Run(after);
    const std::vector<double> continued = slab.Rows();
    if (Rank(World()) == 0) {
      ASSERT_EQ(restored.size(), written.size());
      for (std::size_t i = 0; i < written.size(); ++i)
        ASSERT_EQ(std::bit_cast<std::uint64_t>(restored[i]),
                  std::bit_cast<std::uint64_t>(written[i]))
            << label << ": value " << i;
      const int width = EpState::RowWidth(slab.tissue->cell());
      const std::size_t nodes = written.size() / static_cast<std::size_t>(width);
      const int k = slab.tissue->cell().num_states();
      const std::size_t v = static_cast<std::size_t>(slab.tissue->cell().v_index()) * nodes;
      const std::size_t activation = static_cast<std::size_t>(k) * nodes;
      double worst_t = 0, worst_v = 0;
      int activated = 0, activated_before = 0;
      for (std::size_t i = 0; i < nodes; ++i) activated_before += written[activation + i] >= 0;
      for (std::size_t i = 0; i < nodes; ++i) {
        worst_v = std::max(worst_v, std::abs(continued[v + i] - reference[v + i]));
        ASSERT_EQ(continued[activation + i] >= 0, reference[activation + i] >= 0) << "node " << i;
        if (reference[activation + i] < 0) continue;
        ++activated;
        worst_t =
            std::max(worst_t, std::abs(continued[activation + i] - reference[activation + i]));
      }
      EXPECT_LE(worst_t, 1e-5) << label;
      EXPECT_LE(worst_v, 1e-2) << label;
      EXPECT_GT(activated, 3 * activated_before) << label;
      std::printf(
          "[ %s ] %d of %zu nodes activated (%d at the checkpoint); largest differences %.3g ms, "
          "%.3g mV\n",
          label.c_str(), activated, nodes, activated_before, worst_t, worst_v);
    }
  }
  MPI_Barrier(World());
  if (Rank(World()) == 0) std::filesystem::remove_all(folder);
}

TEST(CheckpointRanks, ASlabsStateMovesToMoreRanksAndRunsOn) {
  const int world = Size(World());
  MovesAndRunsOn({world / 2, world, true}, "part-only, fewer to more");
  MovesAndRunsOn({world / 2, world, false}, "whole view, fewer to more");
}

TEST(CheckpointRanks, ASlabsStateMovesToFewerRanksAndRunsOn) {
  const int world = Size(World());
  MovesAndRunsOn({world, world - 1, true}, "part-only, more to fewer");
  if (world > 2) MovesAndRunsOn({world - 1, world / 2, false}, "whole view, 3 to 2");
}

// Displacements and velocities of every node (a view gathers them on every rank).
Eigen::MatrixXd Motion(const SimObject& object) {
  Eigen::MatrixXd out(6, object.domain().num_nodes());
  for (int k = 0; k < 2; ++k) {
    const FieldId id = object.FindField(k == 0 ? "displacement" : "velocity");
    Eigen::MatrixXd values(3, out.cols());
    object.ReadField(id, values);
    out.middleRows(3 * k, 3) = values;
  }
  return out;
}

struct SplitCantilever {
  std::shared_ptr<const Mesh> whole = CantileverMesh();
  std::unique_ptr<WholeDomainView> view;
  explicit SplitCantilever(MPI_Comm comm) {
    FemParams p = CantileverParams();
    p.linear_solver.preconditioner = "amg";
    auto distribution = std::make_shared<DistributedSolid>(whole, comm);
    p.distribution = distribution;
    const MeshPart& part = distribution->part();
    view = std::make_unique<WholeDomainView>(
        std::make_unique<FemSolid>("beam", part.mesh, std::move(p)), part, whole, comm,
        WholeDomainView::BoundaryMap{distribution->whole_boundary_vertex(),
                                     distribution->whole_boundary_face()});
    Clamp(*view);
  }
  void Run(int steps) const {
    for (int s = 0; s < steps; ++s) ASSERT_TRUE(view->Step(5e-3).ok());
  }
  [[nodiscard]] Eigen::MatrixXd Motion() const { return gipsi::Motion(*view); }
};

// Checkpointed after 20 steps of 5 ms on N ranks and restored on M: the motion is the written
// one bit for bit; 20 steps on, through the first swing, it is the uninterrupted run's within
// 1e-9 of the 7 cm sag (both solve each step to 1e-11; the moved run's first Newton solve
// starts without the warm start; distributed_solid_test.cc argues the bound).
TEST(CheckpointRanks, ACantileversStateMovesAndSwingsOn) {
  const int world = Size(World());
  for (const auto& [from, to] : {std::pair{world / 2, world}, std::pair{world, world - 1}}) {
    const std::filesystem::path folder = Folder(fmt::format("beam{}to{}", from, to));
    std::vector<std::filesystem::path> files;
    Eigen::MatrixXd written, reference;
    {
      const FirstRanks writers(from);
      if (writers.member()) {
        const SplitCantilever beam(writers.comm());
        beam.Run(20);
        files = Write(*beam.view, writers.comm(), folder);
        written = beam.Motion();
        beam.Run(20);
        reference = beam.Motion();
      }
    }
    files.clear();
    for (int r = 0; r < from; ++r) files.push_back(folder / fmt::format("p{}", r));
    const FirstRanks readers(to);
    if (readers.member()) {
      const SplitCantilever beam(readers.comm());
      Restore(*beam.view, readers.comm(), files);
      const Eigen::MatrixXd restored = beam.Motion();
      beam.Run(20);
      const Eigen::MatrixXd continued = beam.Motion();
      if (Rank(World()) == 0) {
        ASSERT_EQ(restored.cols(), written.cols());
        for (Index i = 0; i < written.size(); ++i)
          ASSERT_EQ(std::bit_cast<std::uint64_t>(restored.data()[i]),
                    std::bit_cast<std::uint64_t>(written.data()[i]))
              << from << " to " << to << ": value " << i;
        const double sag = -reference.row(2).minCoeff();
        EXPECT_GT(sag, 0.01);
        const double worst = (continued.topRows(3) - reference.topRows(3)).cwiseAbs().maxCoeff();
        EXPECT_LE(worst, 1e-9 * sag) << from << " to " << to;
        std::printf("[ beam %d to %d ] sag %.4g m; largest difference %.3g m\n", from, to, sag,
                    worst);
      }
    }
    MPI_Barrier(World());
    if (Rank(World()) == 0) std::filesystem::remove_all(folder);
  }
}

// The rows of a serial monodomain's state, column after column (as SplitSlab::Rows).
std::vector<double> Columns(const Monodomain& tissue) {
  const auto width = static_cast<std::size_t>(EpState::RowWidth(tissue.cell()));
  const std::vector<double> rows = tissue.state().ToRows();
  const std::size_t nodes = rows.size() / width;
  std::vector<double> columns(rows.size());
  for (std::size_t i = 0; i < nodes; ++i)
    for (std::size_t j = 0; j < width; ++j) columns[j * nodes + i] = rows[i * width + j];
  return columns;
}

// A serial run's checkpoint (one file, the serial objects' state) restored on every rank of the
// world: the slab's monodomain (part-only and whole view) and the cantilever's solid take their
// parts of it, bit for bit, and run on as the serial run does within the bounds of the moves
// above (the split solves sum in other orders; the solid's first Newton solve starts afresh).
TEST(CheckpointRanks, ASerialRunsStateMovesToTheRanks) {
  const std::filesystem::path folder = Folder("serial");
  const std::vector<std::filesystem::path> files = {folder / "serial.gck"};
  const long before = 1000, after = 2000;
  std::vector<double> written, reference;
  Eigen::MatrixXd beam_written, beam_reference;
  if (Rank(World()) == 0) {
    Monodomain slab("slab", std::make_shared<Mesh>(MakeTetBox(Vec3::Zero(), kSize, {40, 14, 6})),
                    SlabParams());
    for (long s = 0; s < before; ++s) ASSERT_TRUE(slab.Step(kDt).ok());
    StateWriter out;
    slab.SaveState(out);
    WriteCheckpointFile(files[0], out.bytes());
    written = Columns(slab);
    for (long s = 0; s < after; ++s) ASSERT_TRUE(slab.Step(kDt).ok());
    reference = Columns(slab);
    FemSolid beam("beam", CantileverMesh(), CantileverParams());
    Clamp(beam);
    for (int s = 0; s < 20; ++s) ASSERT_TRUE(beam.Step(5e-3).ok());
    StateWriter beam_out;
    beam.SaveState(beam_out);
    WriteCheckpointFile(folder / "beam.gck", beam_out.bytes());
    beam_written = Motion(beam);
    for (int s = 0; s < 20; ++s) ASSERT_TRUE(beam.Step(5e-3).ok());
    beam_reference = Motion(beam);
  }
  MPI_Barrier(World());
  for (bool part_only : {true, false}) {
    const SplitSlab slab(World(), part_only);
    Restore(*slab.view, World(), files);
    EXPECT_NEAR(slab.view->time(), before * kDt, 1e-15);
    EXPECT_EQ(slab.tissue->step_count(), before);
    const std::vector<double> restored = slab.Rows();
    slab.Run(after);
    const std::vector<double> continued = slab.Rows();
    if (Rank(World()) != 0) continue;
    ASSERT_EQ(restored.size(), written.size());
    for (std::size_t i = 0; i < written.size(); ++i)
      ASSERT_EQ(std::bit_cast<std::uint64_t>(restored[i]), std::bit_cast<std::uint64_t>(written[i]))
          << "part-only " << part_only << ": value " << i;
    const std::size_t nodes =
        written.size() / static_cast<std::size_t>(EpState::RowWidth(slab.tissue->cell()));
    const std::size_t activation =
        static_cast<std::size_t>(slab.tissue->cell().num_states()) * nodes;
    const std::size_t v = static_cast<std::size_t>(slab.tissue->cell().v_index()) * nodes;
    double worst_t = 0, worst_v = 0;
    for (std::size_t i = 0; i < nodes; ++i) {
      worst_v = std::max(worst_v, std::abs(continued[v + i] - reference[v + i]));
      ASSERT_EQ(continued[activation + i] >= 0, reference[activation + i] >= 0) << "node " << i;
      if (reference[activation + i] >= 0)
        worst_t =
            std::max(worst_t, std::abs(continued[activation + i] - reference[activation + i]));
    }
    EXPECT_LE(worst_t, 1e-5);
    EXPECT_LE(worst_v, 1e-2);
    std::printf("[ serial slab to %d ranks, part-only %d ] largest differences %.3g ms, %.3g mV\n",
                Size(World()), part_only, worst_t, worst_v);
  }
  const SplitCantilever beam(World());
  Restore(*beam.view, World(), {folder / "beam.gck"});
  const Eigen::MatrixXd restored = beam.Motion();
  beam.Run(20);
  const Eigen::MatrixXd continued = beam.Motion();
  if (Rank(World()) == 0) {
    for (Index i = 0; i < beam_written.size(); ++i)
      ASSERT_EQ(std::bit_cast<std::uint64_t>(restored.data()[i]),
                std::bit_cast<std::uint64_t>(beam_written.data()[i]))
          << "beam: value " << i;
    const double sag = -beam_reference.row(2).minCoeff();
    EXPECT_GT(sag, 0.01);
    const double worst = (continued.topRows(3) - beam_reference.topRows(3)).cwiseAbs().maxCoeff();
    EXPECT_LE(worst, 1e-9 * sag);
    std::printf("[ serial beam to %d ranks ] sag %.4g m; largest difference %.3g m\n",
                Size(World()), sag, worst);
  }
  MPI_Barrier(World());
  if (Rank(World()) == 0) std::filesystem::remove_all(folder);
}

// The other way: a distributed run's checkpoint (every rank's file) read by a run on one process
// (rank 0 here, alone): the serial objects gather the split ones' parts, bit for bit, and run on
// as the split runs do within the bounds above.
TEST(CheckpointRanks, ADistributedRunsPartsGatherInTheSerialObject) {
  const long before = 1000, after = 2000;
  auto read = [](SimObject& object, const std::vector<std::filesystem::path>& files) {
    SetCheckpointPieces(files);
    StateReader in(ReadCheckpointFile(files[0]), files[0].string());
    object.RestoreState(in);
    SetCheckpointPieces({});
  };
  for (bool part_only : {true, false}) {
    const std::filesystem::path folder = Folder(fmt::format("gathered{}", part_only));
    std::vector<std::filesystem::path> files;
    std::vector<double> written, reference;
    {
      const SplitSlab slab(World(), part_only);
      slab.Run(before);
      files = Write(*slab.view, World(), folder);
      written = slab.Rows();
      slab.Run(after);
      reference = slab.Rows();
    }
    MPI_Barrier(World());
    if (Rank(World()) == 0) {
      Monodomain serial("slab",
                        std::make_shared<Mesh>(MakeTetBox(Vec3::Zero(), kSize, {40, 14, 6})),
                        SlabParams());
      read(serial, files);
      EXPECT_NEAR(serial.time(), before * kDt, 1e-15);
      EXPECT_EQ(serial.step_count(), before);
      const std::vector<double> restored = Columns(serial);
      ASSERT_EQ(restored.size(), written.size());
      for (std::size_t i = 0; i < written.size(); ++i)
        ASSERT_EQ(std::bit_cast<std::uint64_t>(restored[i]),
                  std::bit_cast<std::uint64_t>(written[i]))
            << "part-only " << part_only << ": value " << i;
      for (long s = 0; s < after; ++s) ASSERT_TRUE(serial.Step(kDt).ok());
      const std::vector<double> continued = Columns(serial);
      const std::size_t nodes =
          written.size() / static_cast<std::size_t>(EpState::RowWidth(serial.cell()));
      const std::size_t activation = static_cast<std::size_t>(serial.cell().num_states()) * nodes;
      double worst_t = 0;
      for (std::size_t i = 0; i < nodes; ++i) {
        ASSERT_EQ(continued[activation + i] >= 0, reference[activation + i] >= 0) << "node " << i;
        if (reference[activation + i] >= 0)
          worst_t =
              std::max(worst_t, std::abs(continued[activation + i] - reference[activation + i]));
      }
      EXPECT_LE(worst_t, 1e-5);
      std::printf("[ %d ranks' slab on one process, part-only %d ] largest difference %.3g ms\n",
                  Size(World()), part_only, worst_t);
    }
    MPI_Barrier(World());
    if (Rank(World()) == 0) std::filesystem::remove_all(folder);
  }
  const std::filesystem::path folder = Folder("gathered_beam");
  std::vector<std::filesystem::path> files;
  Eigen::MatrixXd written, reference;
  {
    const SplitCantilever beam(World());
    beam.Run(20);
    files = Write(*beam.view, World(), folder);
    written = beam.Motion();
    beam.Run(20);
    reference = beam.Motion();
  }
  MPI_Barrier(World());
  if (Rank(World()) == 0) {
    FemSolid beam("beam", CantileverMesh(), CantileverParams());
    Clamp(beam);
    read(beam, files);
    const Eigen::MatrixXd restored = Motion(beam);
    for (Index i = 0; i < written.size(); ++i)
      ASSERT_EQ(std::bit_cast<std::uint64_t>(restored.data()[i]),
                std::bit_cast<std::uint64_t>(written.data()[i]))
          << "beam: value " << i;
    for (int s = 0; s < 20; ++s) ASSERT_TRUE(beam.Step(5e-3).ok());
    const double sag = -reference.row(2).minCoeff();
    const double worst = (Motion(beam).topRows(3) - reference.topRows(3)).cwiseAbs().maxCoeff();
    EXPECT_LE(worst, 1e-9 * sag);
    std::printf("[ %d ranks' beam on one process ] sag %.4g m; largest difference %.3g m\n",
                Size(World()), sag, worst);
  }
  MPI_Barrier(World());
  if (Rank(World()) == 0) std::filesystem::remove_all(folder);
}

// A set of files that is not one checkpoint of this mesh is refused on every rank, by a message
// that says what is wrong: one file too many, or another mesh's.
TEST(CheckpointRanks, FilesOfAnotherMeshOrAnIncompleteSetAreRefused) {
  const int world = Size(World());
  const std::filesystem::path folder = Folder("refused");
  std::vector<std::filesystem::path> files;
  {
    const FirstRanks writers(world == 2 ? 1 : 3);
    if (writers.member()) {
      const SplitSlab slab(writers.comm(), true, {40, 14, 7});  // another mesh
      slab.Run(5);
      files = Write(*slab.view, writers.comm(), folder);
    }
  }
  int count = static_cast<int>(files.size());
  MPI_Bcast(&count, 1, MPI_INT, 0, World());
  files.clear();
  for (int r = 0; r < count; ++r) files.push_back(folder / fmt::format("p{}", r));
  const FirstRanks readers(2);  // another count than the writers'
  if (readers.member()) {
    const SplitSlab slab(readers.comm(), true);
    auto refused = [&](const std::vector<std::filesystem::path>& set, const std::string& what) {
      try {
        Restore(*slab.view, readers.comm(), set);
        ADD_FAILURE() << "restored: " << what;
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      }
    };
    std::vector<std::filesystem::path> too_many = files;
    too_many.push_back(files.front());
    refused(too_many, "the checkpoint's parts were written on");
    refused(files, "boundary faces, and this scene's has");
    EXPECT_EQ(slab.view->time(), 0.0);  // nothing restored
  }
  MPI_Barrier(World());
  if (Rank(World()) == 0) std::filesystem::remove_all(folder);
}

}  // namespace
}  // namespace gipsi
