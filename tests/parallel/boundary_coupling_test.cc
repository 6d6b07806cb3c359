// A BoundaryCoupling between split solids (models/connectors/boundary_coupling.h,
// PartitionedObject::InterpolateOnBoundary): two pieces of a cantilever meshed apart and glued
// through their shared face give the serial coupling's motion whichever end is made in blocks,
// the forces the driver receives are the follower's reactions to rounding (the transpose), and
// a bad interface is refused on every rank alike. Runs under `mpiexec -np 2` and `-np 4
// --oversubscribe` (tests/CMakeLists.txt); every test is collective.

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <array>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/geometry/region.h"
#include "gipsi/models/connectors/boundary_coupling.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/parallel/distributed_solid.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/parallel_session.h"
#include "gipsi/parallel/whole_domain_view.h"
#include "parallel/cantilever.h"

namespace gipsi {
namespace {

MPI_Comm World() { return ParallelSession::world(); }

// The driver: the cantilever's first 5 cm (10 × 2 × 2 cells), clamped at x = 0. The follower:
// a 3 × 1 × 0.5 cm block on another grid (5 × 3 × 2 cells, none matching the driver's), resting
// on the driver's top face from x = 2 to 5 cm, so that the driver's cut crosses the interface
// (its vertices there are shared by several parts). Both cut into 5 tets per cell, as the
// scenes' boxes.
struct Piece {
  Vec3 lo, hi;
  std::array<int, 3> cells;
};
const Piece kDriver{Vec3::Zero(), Vec3(0.05, 0.01, 0.01), {10, 2, 2}};
const Piece kFollower{Vec3(0.02, 0, 0.01), Vec3(0.05, 0.01, 0.015), {5, 3, 2}};

std::shared_ptr<const Mesh> WholeMesh(const Piece& piece) {
  return std::make_shared<Mesh>(MakeTetBox(piece.lo, piece.hi, piece.cells, HexSplit::kFive));
}

// The serial piece (the same on every rank), or a view on this rank's part of it made from
// blocks, with no whole mesh on any rank (as a scene run makes an object in blocks).
std::unique_ptr<SimObject> MakePiece(const std::string& name, const Piece& piece, bool in_blocks) {
  FemParams p = test::CantileverParams();
  std::unique_ptr<SimObject> object;
  if (!in_blocks) {
    object = std::make_unique<FemSolid>(name, WholeMesh(piece), std::move(p));
  } else {
    auto distribution = std::make_shared<DistributedSolid>(
        PartitionMeshBlocks(
            MakeTetBoxBlock(piece.lo, piece.hi, piece.cells, HexSplit::kFive,
                            ParallelSession::rank(World()), ParallelSession::size(World())),
            World()),
        World());
    p.distribution = distribution;
    const MeshPart& part = distribution->part();
    object = std::make_unique<WholeDomainView>(
        std::make_unique<FemSolid>(name, part.mesh, std::move(p)), part, World(),
        WholeDomainView::BoundaryMap{
            distribution->whole_boundary_vertex(), distribution->whole_boundary_face(),
            distribution->whole_boundary_vertices(), distribution->whole_boundary_faces()});
  }
  if (piece.lo.x() == 0) test::Clamp(*object);
  return object;
}

// Every node's displacement of a piece, in the whole mesh's order, on every rank.
Eigen::MatrixXd WholeDisplacement(const SimObject& object, const Piece& piece) {
  const FieldId u = object.FindField("displacement");
  const auto* split = dynamic_cast<const PartitionedObject*>(&object);
  if (split == nullptr) {
    Eigen::MatrixXd out(3, object.FieldCount(u));
    object.ReadField(u, out);
    return out;
  }
  std::vector<int> all(static_cast<std::size_t>(WholeMesh(piece)->num_nodes()));
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  Eigen::MatrixXd out(3, static_cast<Index>(all.size()));
  split->ReadWholeNodes(u, all, out);
  return out;
}

// The sum over every rank of `f`'s columns at the boundary vertices `object`'s rank counts
// (a part's: those whose node it owns; a serial object's: all of them, on rank 0 only).
Vec3 SumCounted(const SimObject& object, const Eigen::MatrixXd& f) {
  const auto* split = dynamic_cast<const PartitionedObject*>(&object);
  const BoundarySurface& b = object.boundary();
  Vec3 sum = Vec3::Zero();
  if (split != nullptr || ParallelSession::rank(World()) == 0)
    for (Index v = 0; v < b.num_vertices(); ++v)
      if (split == nullptr ||
          b.vertex_to_node[static_cast<std::size_t>(v)] < split->num_owned_nodes())
        sum += f.col(v);
  MPI_Allreduce(MPI_IN_PLACE, sum.data(), 3, MPI_DOUBLE, MPI_SUM, World());
  return sum;
}

// The coupling forces the connector put on `object`'s boundary vertices.
Eigen::MatrixXd CouplingForces(const SimObject& object) {
  const BoundaryConditions& bc = object.boundary_conditions();
  Eigen::MatrixXd out(3, object.boundary().num_vertices());
  for (Index v = 0; v < out.cols(); ++v) out.col(v) = bc.force(v) - bc.applied().force.col(v);
  return out;
}

Eigen::MatrixXd Read(const SimObject& object, const std::string& field) {
  const FieldId id = object.FindField(field);
  Eigen::MatrixXd out(3, object.FieldCount(id));
  object.ReadField(id, out);
  return out;
}

// The glued cantilever released under gravity for `steps` steps of 5 ms (the connector fires
// before each, as a scene's order "glue, driver, follower" does, at each macro step's start).
// Returns both pieces' displacements in their whole meshes' order; checks, at every firing after
// the first, that the driver received the follower's reactions in total (the transpose conserves
// force).
struct Glued {
  Eigen::MatrixXd driver_u, follower_u;
  std::int64_t interface_vertices = 0;
};
Glued RunGlued(bool driver_in_blocks, bool follower_in_blocks, int steps) {
  std::unique_ptr<SimObject> driver = MakePiece("driver", kDriver, driver_in_blocks);
  std::unique_ptr<SimObject> follower = MakePiece("follower", kFollower, follower_in_blocks);
  BoundaryCoupling glue("glue", *driver, *follower, std::nullopt, -1);
  EXPECT_EQ(glue.couples_parts(), driver_in_blocks || follower_in_blocks);
  Glued out;
  // Interface vertices counted once: each by its node's owner on a part, once for a whole one.
  const auto* split = dynamic_cast<const PartitionedObject*>(follower.get());
  for (const int v : glue.interface_vertices())
    if (split != nullptr ? follower->boundary().vertex_to_node[static_cast<std::size_t>(v)] <
                               split->num_owned_nodes()
                         : ParallelSession::rank(World()) == 0)
      ++out.interface_vertices;
  MPI_Allreduce(MPI_IN_PLACE, &out.interface_vertices, 1, MPI_INT64_T, MPI_SUM, World());
  for (int s = 0; s < steps; ++s) {
    driver->BeginMacroStep();  // as the kernel does: the last step's coupling loads go
    follower->BeginMacroStep();
    EXPECT_TRUE(glue.Fire(0.005 * s).ok());
    if (s > 0) {
      const Vec3 given = SumCounted(*driver, CouplingForces(*driver));
      // The follower's reactions at the interface vertices (those it counts).
      Eigen::MatrixXd r = Read(*follower, "reaction_force");
      std::vector<char> on(static_cast<std::size_t>(r.cols()), 0);
      for (const int v : glue.interface_vertices()) on[static_cast<std::size_t>(v)] = 1;
      for (Index v = 0; v < r.cols(); ++v)
        if (on[static_cast<std::size_t>(v)] == 0) r.col(v).setZero();
      const Vec3 reactions = SumCounted(*follower, r);
      EXPECT_GT(reactions.norm(), 1e-4) << "step " << s;  // N: about the follower's weight
      EXPECT_LE((given + reactions).norm(), 1e-12 * reactions.norm()) << "step " << s;
    }
    EXPECT_TRUE(driver->Step(0.005).ok());
    EXPECT_TRUE(follower->Step(0.005).ok());
  }
  out.driver_u = WholeDisplacement(*driver, kDriver);
  out.follower_u = WholeDisplacement(*follower, kFollower);
  return out;
}

// Each end made in blocks, or both, the serial coupling's motion within the solvers' tolerance
// (Newton and CG to 1e-11 per step: after 10 steps the runs agree to about 1e-9 of the sag).
TEST(SplitBoundaryCoupling, GluesSolidsMadeInBlocksAsTheSerialCoupling) {
  const int steps = 10;
  const Glued serial = RunGlued(false, false, steps);
  const double sag = serial.follower_u.cwiseAbs().maxCoeff();
  ASSERT_GT(sag, 1e-3);                      // m: the follower hangs from the sagging driver
  ASSERT_EQ(serial.interface_vertices, 24);  // the follower's 6 × 4 vertices at z = 1 cm
  for (const auto& [driver_in_blocks, follower_in_blocks] :
       std::vector<std::pair<bool, bool>>{{true, true}, {true, false}, {false, true}}) {
    SCOPED_TRACE(std::string("driver ") + (driver_in_blocks ? "in blocks" : "whole") +
                 ", follower " + (follower_in_blocks ? "in blocks" : "whole"));
    const Glued split = RunGlued(driver_in_blocks, follower_in_blocks, steps);
    EXPECT_EQ(split.interface_vertices, serial.interface_vertices);
    EXPECT_LE((split.driver_u - serial.driver_u).cwiseAbs().maxCoeff(), 1e-8 * sag);
    EXPECT_LE((split.follower_u - serial.follower_u).cwiseAbs().maxCoeff(), 1e-8 * sag);
  }
}

// A follower region with vertices off the driver's boundary is refused on every rank, naming
// the first such vertex's node, as the serial connector refuses it.
std::string Refusal(bool in_blocks, const Region& region) {
  std::unique_ptr<SimObject> driver = MakePiece("driver", kDriver, in_blocks);
  std::unique_ptr<SimObject> follower = MakePiece("follower", kFollower, in_blocks);
  try {
    BoundaryCoupling glue("glue", *driver, *follower, region, -1);
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(SplitBoundaryCoupling, ARegionOffTheInterfaceIsRefusedOnEveryRank) {
  const Region whole_follower = BoxRegion{Vec3(-1, -1, 0.009), Vec3(1, 1, 1)};
  const std::string serial = Refusal(false, whole_follower);
  EXPECT_NE(serial.find("from the driver's boundary, more than the tolerance"), std::string::npos)
      << serial;
  EXPECT_EQ(Refusal(true, whole_follower), serial);
  // Only its face at z = 1 cm: accepted, with every vertex there.
  std::unique_ptr<SimObject> driver = MakePiece("driver", kDriver, true);
  std::unique_ptr<SimObject> follower = MakePiece("follower", kFollower, true);
  const Region face = BoxRegion{Vec3(-1, -1, 0.009), Vec3(1, 1, 0.011)};
  BoundaryCoupling glue("glue", *driver, *follower, face, -1);
  std::int64_t count = static_cast<std::int64_t>(glue.interface_vertices().size());
  MPI_Allreduce(MPI_IN_PLACE, &count, 1, MPI_INT64_T, MPI_SUM, World());
  EXPECT_GE(count, 24);  // the 6 × 4 vertices of the face, some on several parts
}

}  // namespace
}  // namespace gipsi
