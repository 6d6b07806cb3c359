#include "gipsi/collision/aabb_tree.h"

#include <algorithm>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "collision/collision_test_util.h"
#include "gipsi/collision/proximity.h"

namespace gipsi {
namespace {

using testing_util::Sheet;

// The exact box of triangle t (min and max of its corners: no rounding involved).
Box3 TriangleBox(const Points& x, const Triangles& f, int t) {
  Box3 b;
  for (int k = 0; k < 3; ++k) b.Add(Vec3(x.col(f(k, t))));
  return b;
}

void ExpectSameBox(const Box3& got, const Box3& want) {
  EXPECT_EQ(got.lo, want.lo);
  EXPECT_EQ(got.hi, want.hi);
}

// Checks the tree's structure against the triangles: every triangle in exactly one leaf,
// leaves full except the last in leaf order, and every box the exact union of what it holds.
void ExpectConsistent(const AabbTree& tree, const Points& x, const Triangles& f) {
  const auto& nodes = tree.nodes();
  const int num = static_cast<int>(f.cols());
  std::vector<int> seen(static_cast<std::size_t>(num), 0);
  for (int t : tree.order()) ++seen[static_cast<std::size_t>(t)];
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int c) { return c == 1; }));
  int covered = 0, partial = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const AabbTree::Node& n = nodes[i];
    Box3 want;
    if (n.is_leaf()) {
      covered += n.count;
      if (n.count != tree.leaf_size()) {
        ++partial;
        EXPECT_EQ(n.first + n.count, num) << "only the last leaf may be partly filled";
      }
      for (int p = n.first; p < n.first + n.count; ++p) {
        const Box3 tb = TriangleBox(x, f, tree.order()[static_cast<std::size_t>(p)]);
        ExpectSameBox(tree.ordered_box(p), tb);
        want.Add(tb);
      }
    } else {
      ASSERT_GT(n.first, static_cast<int>(i));  // children after their parent (bottom-up refit)
      want.Add(nodes[static_cast<std::size_t>(n.first)].box);
      want.Add(nodes[static_cast<std::size_t>(n.first) + 1].box);
    }
    ExpectSameBox(n.box, want);
    EXPECT_EQ(n.area, want.SurfaceArea());
  }
  EXPECT_EQ(covered, num);
  EXPECT_LE(partial, 1);
}

TEST(AabbTree, LeavesAreFullExceptTheLastAndBoxesAreExactAfterRefit) {
  // 2 · 13² = 338 triangles: 84 leaves of 4 and one of 2 with leaf size 4.
  CollisionSurface s = Sheet(13, 1.0, Vec3::Zero());
  AabbTree tree;
  tree.Build(s.positions(), s.triangles(), 4);
  ExpectConsistent(tree, s.positions(), s.triangles());
  EXPECT_EQ(tree.nodes().size(), 2u * 85u - 1u);  // a binary tree over 85 leaves
  // Deform, refit (topology kept), and check again; a flat sheet has zero-thickness boxes, so
  // any bending raises the summed inner area above that of the build.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  Points& x = s.positions();
  for (Index v = 0; v < x.cols(); ++v) x.col(v) += Vec3(u(rng), u(rng), 5 * u(rng));
  tree.Refit(x, s.triangles());
  ExpectConsistent(tree, x, s.triangles());
  EXPECT_GT(tree.quality_ratio(), 1.0);
  for (int leaf_size : {1, 3, 8}) {
    AabbTree other;
    other.Build(x, s.triangles(), leaf_size);
    EXPECT_EQ(other.leaf_size(), leaf_size);
    ExpectConsistent(other, x, s.triangles());
  }
}

// Query and brute force run the same exact leaf computations: every field must agree bit for
// bit (the tree only decides which pairs reach them, and each feature pair is owned once).
void ExpectIdentical(const ProximityResult& got, const ProximityResult& want) {
  auto same_vt = [](const std::vector<VertexTriangleContact>& g,
                    const std::vector<VertexTriangleContact>& w) {
    ASSERT_EQ(g.size(), w.size());
    for (std::size_t i = 0; i < g.size(); ++i) {
      EXPECT_EQ(g[i].vertex, w[i].vertex);
      EXPECT_EQ(g[i].triangle, w[i].triangle);
      EXPECT_EQ(g[i].distance, w[i].distance);
      EXPECT_EQ(g[i].bary, w[i].bary);
      EXPECT_EQ(g[i].closest, w[i].closest);
    }
  };
  same_vt(got.a_on_b, want.a_on_b);
  same_vt(got.b_on_a, want.b_on_a);
  ASSERT_EQ(got.edges.size(), want.edges.size());
  for (std::size_t i = 0; i < got.edges.size(); ++i) {
    EXPECT_EQ(got.edges[i].edge_a, want.edges[i].edge_a);
    EXPECT_EQ(got.edges[i].edge_b, want.edges[i].edge_b);
    EXPECT_EQ(got.edges[i].s, want.edges[i].s);
    EXPECT_EQ(got.edges[i].t, want.edges[i].t);
    EXPECT_EQ(got.edges[i].distance, want.edges[i].distance);
  }
}

TEST(ProximityQuery, RandomlyDeformedSheetsMatchBruteForceExactly) {
  // Two sheets of 2 · 19² and 2 · 23² triangles (both leave a partly filled last leaf), every
  // vertex jittered randomly in 3D by up to half a cell, so the contacts include all feature
  // kinds (vertex–face, vertex–edge, vertex–vertex, edge–edge) at random angles.
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> u(-1, 1);
  ProximityQuery query;
  ProximityResult got, want;
  std::size_t vertex_contacts = 0, edge_contacts = 0;
  for (int trial = 0; trial < 4; ++trial) {
    CollisionSurface a = Sheet(19, 1.0, Vec3::Zero());
    CollisionSurface b = Sheet(23, 1.0, Vec3(0.011, -0.017, 0.004));
    for (CollisionSurface* s : {&a, &b}) {
      const double cell = s == &a ? 1.0 / 19 : 1.0 / 23;
      for (Index v = 0; v < s->num_vertices(); ++v)
        s->positions().col(v) += 0.5 * cell * Vec3(u(rng), u(rng), u(rng));
    }
    a.Update(1.5, false);
    b.Update(1.5, false);
    const double thickness = 0.01 + 0.005 * trial;
    query.Query(a, b, thickness, true, got);
    BruteForceProximity(a, b, thickness, true, false, want);
    ExpectIdentical(got, want);
    vertex_contacts += got.a_on_b.size() + got.b_on_a.size();
    edge_contacts += got.edges.size();
  }
  // The test exercises many contacts of both kinds.
  EXPECT_GT(vertex_contacts, 200u);
  EXPECT_GT(edge_contacts, 200u);
}

}  // namespace
}  // namespace gipsi
