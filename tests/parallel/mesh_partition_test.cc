// The partitioner (parallel/mesh_partition.h) under MPI: a whole mesh cut over the ranks, and a
// mesh given as one block per rank (geometry/mesh_block.h) cut without any rank holding it
// whole. Every test is collective.

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <numeric>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/parallel_session.h"

namespace gipsi {
namespace {

MPI_Comm World() { return ParallelSession::world(); }
int Rank() { return ParallelSession::rank(World()); }
int Size() { return ParallelSession::size(World()); }

const Vec3 kSlab(0.020, 0.007, 0.003);

std::shared_ptr<const Mesh> Slab(int cells_per_mm_x2) {
  const int n = cells_per_mm_x2;
  return std::make_shared<Mesh>(MakeTetBox(Vec3::Zero(), kSlab, {20 * n, 7 * n, 3 * n}));
}

TEST(MeshPartition, EveryTetOnceEveryNodeOwnedOnceAndTheTetsBalanced) {
  const auto whole = Slab(2);
  const MeshPart part = PartitionMesh(*whole, World());
  // Tets and owned nodes add up; the owned blocks tile [0, N).
  std::int64_t counts[2] = {static_cast<std::int64_t>(part.whole_tet.size()), part.num_owned};
  MPI_Allreduce(MPI_IN_PLACE, counts, 2, MPI_INT64_T, MPI_SUM, World());
  EXPECT_EQ(counts[0], whole->num_tets());
  EXPECT_EQ(counts[1], whole->num_nodes());
  std::int64_t next_first = part.first_owned + part.num_owned;
  std::vector<std::int64_t> firsts(static_cast<std::size_t>(Size()));
  MPI_Allgather(&part.first_owned, 1, MPI_INT64_T, firsts.data(), 1, MPI_INT64_T, World());
  EXPECT_EQ(firsts[0], 0);
  if (Rank() + 1 < Size()) {
    EXPECT_EQ(firsts[static_cast<std::size_t>(Rank()) + 1], next_first);
  }
  // Every tet on exactly one rank: the sum of the ranks' tet-index sums is the whole one.
  std::int64_t sum = std::accumulate(part.whole_tet.begin(), part.whole_tet.end(), std::int64_t{0});
  MPI_Allreduce(MPI_IN_PLACE, &sum, 1, MPI_INT64_T, MPI_SUM, World());
  const std::int64_t e = whole->num_tets();
  EXPECT_EQ(sum, e * (e - 1) / 2);
  // Local tets use the local copies of the whole mesh's nodes at the same positions.
  for (Index t = 0; t < part.mesh->num_tets(); ++t)
    for (int a = 0; a < 4; ++a) {
      const int local = part.mesh->tets(a, t);
      ASSERT_EQ(part.whole_node[static_cast<std::size_t>(local)],
                whole->tets(a, part.whole_tet[static_cast<std::size_t>(t)]));
    }
  // Shared nodes belong to lower ranks (the owner is the lowest rank using the node).
  std::vector<std::int64_t> first_of(firsts);
  for (std::int64_t i = part.num_owned; i < part.num_local(); ++i) {
    const std::int64_t g = part.global[static_cast<std::size_t>(i)];
    EXPECT_LT(g, part.first_owned) << "shared node " << i << " owned by a higher rank";
  }
  // PT-Scotch balances the tet counts (asked for at most 1 % imbalance; 5 % allowed).
  const double mean = static_cast<double>(e) / Size();
  EXPECT_LT(std::abs(static_cast<double>(part.whole_tet.size()) - mean), 0.05 * mean);
}

// Checkpoints of a distributed run restore only on the cut that wrote them, so a second cut of
// the same mesh must be the first: Scotch runs in its deterministic mode with a fixed seed.
// (Its default mode, with Debian's threaded build, cut this slab differently in every call.)
TEST(MeshPartition, CutsTheSameMeshTheSameWayEveryTime) {
  const auto whole = Slab(2);
  const MeshPart first = PartitionMesh(*whole, World());
  for (int again = 0; again < 2; ++again) {
    const MeshPart next = PartitionMesh(*whole, World());
    EXPECT_EQ(next.whole_tet, first.whole_tet);
    EXPECT_EQ(next.whole_node, first.whole_node);
    EXPECT_EQ(next.num_owned, first.num_owned);
  }
}

// The boundary triangles of a part as whole-mesh node triples (each rotated to start at its
// smallest node, so the orientation counts but not the first vertex), with their groups' names.
std::set<std::tuple<int, int, int, std::string>> WholeTriangles(const MeshPart& part) {
  std::set<std::tuple<int, int, int, std::string>> out;
  for (const MeshGroup& g : part.mesh->groups) {
    if (g.dim != 2) continue;
    for (int t : g.items) {
      std::array<int, 3> n{};
      for (int a = 0; a < 3; ++a)
        n[static_cast<std::size_t>(a)] =
            part.whole_node[static_cast<std::size_t>(part.mesh->triangles(a, t))];
      std::rotate(n.begin(), std::min_element(n.begin(), n.end()), n.end());
      out.emplace(n[0], n[1], n[2], g.name);
    }
  }
  return out;
}

// A box made block by block (each rank its own nodes, tets and the triangles of its tets, no
// rank the whole mesh) is cut into the parts of the whole box: the same tets and nodes in the
// same order and numbering, at the same positions, and the same outward boundary triangles in
// the same groups (numbered otherwise: MakeTetBox orders them by box face).
TEST(MeshPartition, ABoxMadeInBlocksIsCutAsTheWholeBox) {
  for (HexSplit split : {HexSplit::kSix, HexSplit::kFive}) {
    const std::array<int, 3> cells{13, 5, 3};  // blocks that start inside a cell
    const Mesh whole = MakeTetBox(Vec3::Zero(), kSlab, cells, split);
    const MeshPart a = PartitionMesh(whole, World());
    const MeshBlock block = MakeTetBoxBlock(Vec3::Zero(), kSlab, cells, split, Rank(), Size());
    EXPECT_EQ(block.num_triangles, whole.num_triangles());
    const MeshPart b = PartitionMeshBlocks(block, World());
    EXPECT_EQ(a.whole_tet, b.whole_tet);
    EXPECT_EQ(a.whole_node, b.whole_node);
    EXPECT_EQ(a.global, b.global);
    EXPECT_EQ(a.num_owned, b.num_owned);
    EXPECT_EQ(a.first_owned, b.first_owned);
    EXPECT_EQ(a.mesh->nodes, b.mesh->nodes);
    EXPECT_EQ(a.mesh->tets, b.mesh->tets);
    EXPECT_EQ(a.mesh->num_triangles(), b.mesh->num_triangles());
    EXPECT_EQ(WholeTriangles(a), WholeTriangles(b));
    ASSERT_EQ(b.mesh->groups.size(), whole.groups.size());
    EXPECT_EQ(b.mesh->groups.back().name, "volume");
    EXPECT_EQ(b.mesh->groups.back().items.size(), b.whole_tet.size());
  }
}

// What a mesh file brings survives the cut: the file's tet ids follow their tets, a node group
// keeps its local nodes, a triangle group its local triangles, and a node no tet uses goes to
// rank 0, which owns it.
TEST(MeshPartition, IdsGroupsAndUnusedNodesSurviveTheCut) {
  Mesh whole = MakeTetBox(Vec3::Zero(), kSlab, {12, 5, 3});
  const int unused = static_cast<int>(whole.num_nodes());
  whole.nodes.conservativeResize(3, unused + 1);
  whole.nodes.col(unused) = Vec3(1, 1, 1);
  const std::vector<int> group{0, 5, 17, 200, unused};
  whole.groups.push_back({"some_nodes", 0, group});
  for (Index e = 0; e < whole.num_tets(); ++e) whole.tet_ids.push_back(1000 + 3 * e);
  whole.tet_id_kind = "Gmsh element tag";
  const MeshPart part = PartitionMesh(whole, World());
  const Mesh& mesh = *part.mesh;
  ASSERT_EQ(mesh.tet_ids.size(), part.whole_tet.size());
  for (std::size_t e = 0; e < part.whole_tet.size(); ++e)
    EXPECT_EQ(mesh.tet_ids[e], 1000 + 3 * part.whole_tet[e]);
  EXPECT_EQ(mesh.tet_id_kind, "Gmsh element tag");
  std::vector<int> expected, got;
  for (std::size_t i = 0; i < part.whole_node.size(); ++i)
    if (std::find(group.begin(), group.end(), part.whole_node[i]) != group.end())
      expected.push_back(static_cast<int>(i));
  ASSERT_NE(mesh.FindGroup("some_nodes"), nullptr);
  EXPECT_EQ(mesh.FindGroup("some_nodes")->items, expected);
  const auto at = std::find(part.whole_node.begin(), part.whole_node.end(), unused);
  EXPECT_EQ(at != part.whole_node.end(), Rank() == 0);
  if (Rank() == 0) {
    EXPECT_LT(at - part.whole_node.begin(), part.num_owned);
    EXPECT_EQ(mesh.nodes.col(at - part.whole_node.begin()), Vec3(1, 1, 1));
  }
  // Each of the whole mesh's triangle groups: the part's triangles are those of the whole group
  // that are a face of a local tet, and every whole triangle is on some rank.
  std::int64_t held = 0;
  for (const MeshGroup& g : mesh.groups)
    if (g.dim == 2) held += static_cast<std::int64_t>(g.items.size());
  MPI_Allreduce(MPI_IN_PLACE, &held, 1, MPI_INT64_T, MPI_SUM, World());
  EXPECT_GE(held, whole.num_triangles());
  for (const MeshGroup& g : mesh.groups) {
    if (g.dim != 2) continue;
    const MeshGroup* w = whole.FindGroup(g.name);
    ASSERT_NE(w, nullptr);
    for (int t : g.items) {
      std::array<int, 3> n{};
      for (int a = 0; a < 3; ++a)
        n[static_cast<std::size_t>(a)] =
            part.whole_node[static_cast<std::size_t>(mesh.triangles(a, t))];
      const bool in_whole_group = std::any_of(w->items.begin(), w->items.end(), [&](int u) {
        return whole.triangles(0, u) == n[0] && whole.triangles(1, u) == n[1] &&
               whole.triangles(2, u) == n[2];
      });
      EXPECT_TRUE(in_whole_group) << g.name << " triangle " << t;
    }
  }
}

// A second-order (curved) mesh is cut on its corners: the split objects run on linear tets,
// which see the corners either way (a quadratic MixedSolid is not split).
TEST(MeshPartition, ASecondOrderMeshIsCutOnItsCorners) {
  EllipsoidShellSpec spec;
  spec.mesh_size = 3;
  spec.order = 2;
  const Mesh whole = MakeEllipsoidShell(spec);
  ASSERT_GT(whole.edge_nodes.cols(), 0);
  const MeshPart part = PartitionMesh(whole, World());
  std::int64_t tets = part.mesh->num_tets();
  MPI_Allreduce(MPI_IN_PLACE, &tets, 1, MPI_INT64_T, MPI_SUM, World());
  EXPECT_EQ(tets, whole.num_tets());
  for (std::size_t i = 0; i < part.whole_node.size(); ++i)
    ASSERT_EQ(part.mesh->nodes.col(static_cast<Index>(i)), whole.nodes.col(part.whole_node[i]));
}

}  // namespace
}  // namespace gipsi
