// The transmural fibre rule solved over the ranks (parallel/distributed_fibres.h) against the
// serial rule on the whole mesh. Runs under `mpiexec -np 2` and `-np 4 --oversubscribe`
// (tests/CMakeLists.txt); every test is collective.

#include "gipsi/parallel/distributed_fibres.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <string>

#include "gipsi/base/error.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/parallel_session.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

MPI_Comm World() { return ParallelSession::world(); }
int Rank() { return ParallelSession::rank(World()); }
int Size() { return ParallelSession::size(World()); }

// The heart scene's left ventricle (scenes/heart.json) at 5 mm: a wall 10 mm thick, two to
// three tets through it.
Mesh Ventricle() {
  EllipsoidShellSpec spec;
  spec.endo_short = 0.022;
  spec.endo_long = 0.048;
  spec.epi_short = 0.032;
  spec.epi_long = 0.058;
  spec.base_z = 0.012;
  spec.mesh_size = 0.005;
  return MakeEllipsoidShell(spec);
}

TransmuralFibreRule Rule() {
  TransmuralFibreRule rule;
  rule.endo = GroupRegion{"endo"};
  rule.epi = GroupRegion{"epi"};
  return rule;
}

// The split rule gives every part's nodes the serial e and its tets the serial fibre and sheet,
// whether the part was cut from the whole mesh or from blocks. CG stops at a residual of 1e-12
// of the right-hand side's: the error in e is at most that times the matrix's condition number,
// which the Dirichlet surfaces on both sides of a wall a few tets thick keep near (thickness /
// h)² times the mesh's grading, well under 1e4, so 1e-8 bounds it. A fibre turns with ∇e,
// which is e's differences over a tet (h) against e's range over the wall: their error is at
// most 1e-8 · thickness / h, a few 1e-8, so 1e-6. The endocardium's and epicardium's nodes keep
// their values exactly, as serially.
TEST(DistributedFibres, EveryPartGetsTheWholeMeshsFibres) {
  const Mesh whole = Ventricle();
  const TransmuralFibreRule rule = Rule();
  const FibreField serial = MakeTransmuralFibres(whole, rule);
  const std::vector<int> endo = SelectNodes(rule.endo, whole), epi = SelectNodes(rule.epi, whole);
  for (const bool in_blocks : {false, true}) {
    SCOPED_TRACE(in_blocks ? "cut from blocks" : "cut from the whole mesh");
    const MeshPart part = in_blocks
                              ? PartitionMeshBlocks(BlockOfMesh(whole, Rank(), Size()), World())
                              : PartitionMesh(whole, World());
    const FibreField split = TransmuralFibresOnPart(part, rule, World());
    ASSERT_EQ(split.transmural.size(), part.num_local());
    ASSERT_EQ(split.fibre.cols(), part.mesh->num_tets());
    double e_error = 0, fibre_error = 0, sheet_error = 0;
    for (std::size_t i = 0; i < part.whole_node.size(); ++i) {
      const int w = part.whole_node[i];
      const double e = split.transmural[static_cast<Index>(i)];
      if (std::binary_search(endo.begin(), endo.end(), w)) {
        EXPECT_EQ(e, 0.0);
      }
      if (std::binary_search(epi.begin(), epi.end(), w)) {
        EXPECT_EQ(e, 1.0);
      }
      e_error = std::max(e_error, std::abs(e - serial.transmural[w]));
    }
    for (std::size_t t = 0; t < part.whole_tet.size(); ++t) {
      const auto local = static_cast<Index>(t);
      fibre_error = std::max(fibre_error,
                             (split.fibre.col(local) - serial.fibre.col(part.whole_tet[t])).norm());
      sheet_error = std::max(sheet_error,
                             (split.sheet.col(local) - serial.sheet.col(part.whole_tet[t])).norm());
    }
    MPI_Allreduce(MPI_IN_PLACE, &e_error, 1, MPI_DOUBLE, MPI_MAX, World());
    MPI_Allreduce(MPI_IN_PLACE, &fibre_error, 1, MPI_DOUBLE, MPI_MAX, World());
    MPI_Allreduce(MPI_IN_PLACE, &sheet_error, 1, MPI_DOUBLE, MPI_MAX, World());
    if (Rank() == 0)
      std::printf("split transmural rule on %d ranks (%s): e within %.3g, fibre %.3g, sheet %.3g\n",
                  Size(), in_blocks ? "blocks" : "whole", e_error, fibre_error, sheet_error);
    EXPECT_LE(e_error, 1e-8);
    EXPECT_LE(fibre_error, 1e-6);
    EXPECT_LE(sheet_error, 1e-6);
  }
}

// The serial rule's refusals, on every rank alike and with the serial messages: a region that
// selects no node of the whole mesh, and a node in both regions (the same node named).
TEST(DistributedFibres, RefusesWhatTheSerialRuleRefuses) {
  const Mesh whole = Ventricle();
  const MeshPart part = PartitionMeshBlocks(BlockOfMesh(whole, Rank(), Size()), World());
  TransmuralFibreRule empty = Rule();
  empty.epi = BoxRegion{Vec3::Constant(1), Vec3::Constant(2)};
  EXPECT_THAT([&] { (void)TransmuralFibresOnPart(part, empty, World()); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("epi region selects no node")));
  TransmuralFibreRule both = Rule();
  both.epi = BoxRegion{Vec3(-1, -1, 0.0), Vec3(1, 1, 1)};  // the base ring's nodes, endo's too
  std::string serial_message;
  try {
    (void)MakeTransmuralFibres(whole, both);
  } catch (const InputError& e) {
    serial_message = e.what();
  }
  ASSERT_THAT(serial_message, HasSubstr("in both the endo and the epi region"));
  EXPECT_THAT([&] { (void)TransmuralFibresOnPart(part, both, World()); },
              ::testing::ThrowsMessage<InputError>(::testing::StrEq(serial_message)));
}

}  // namespace
}  // namespace gipsi
