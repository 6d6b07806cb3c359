#include "gipsi/collision/proximity.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "collision/collision_test_util.h"

namespace gipsi {
namespace {

using testing_util::BoxSurface;
using testing_util::Sheet;

// Query and brute force run the same exact leaf computations, so they must agree bit for bit.
void ExpectSameContacts(const ProximityResult& got, const ProximityResult& want) {
  ASSERT_EQ(got.a_on_b.size(), want.a_on_b.size());
  ASSERT_EQ(got.b_on_a.size(), want.b_on_a.size());
  ASSERT_EQ(got.edges.size(), want.edges.size());
  for (std::size_t i = 0; i < got.a_on_b.size(); ++i) {
    EXPECT_EQ(got.a_on_b[i].vertex, want.a_on_b[i].vertex);
    EXPECT_EQ(got.a_on_b[i].triangle, want.a_on_b[i].triangle);
    EXPECT_EQ(got.a_on_b[i].distance, want.a_on_b[i].distance);
  }
  for (std::size_t i = 0; i < got.b_on_a.size(); ++i) {
    EXPECT_EQ(got.b_on_a[i].vertex, want.b_on_a[i].vertex);
    EXPECT_EQ(got.b_on_a[i].triangle, want.b_on_a[i].triangle);
    EXPECT_EQ(got.b_on_a[i].distance, want.b_on_a[i].distance);
  }
  for (std::size_t i = 0; i < got.edges.size(); ++i) {
    EXPECT_EQ(got.edges[i].edge_a, want.edges[i].edge_a);
    EXPECT_EQ(got.edges[i].edge_b, want.edges[i].edge_b);
    EXPECT_EQ(got.edges[i].distance, want.edges[i].distance);
  }
}

// Two wavy sheets that cross each other along curves.
void Deform(CollisionSurface& s, double amplitude, double phase) {
  Points& x = s.positions();
  for (Index v = 0; v < x.cols(); ++v)
    x(2, v) = amplitude * std::sin(7 * x(0, v) + phase) * std::cos(5 * x(1, v) - phase);
}

TEST(ProximityQuery, SphereOnAPlaneTouchesTheKnownVertexSet) {
  // Grid spacing 0.1; a sphere of radius R = 0.3 touches the plane z = 0 at the grid vertex
  // (0.5, 0.5). A vertex at planar distance r has gap sqrt(r² + R²) − R. With thickness 0.02
  // the gap is below it for r² < d² + 2 d R = 0.0124 (r < 0.111): the touching vertex and its 4
  // axis neighbours (r = 0.1), not the diagonal ones (r = 0.141).
  CollisionSurface plane = Sheet(10, 1.0, Vec3::Zero());
  plane.Update(2.0, false);
  ProximityQuery query;
  std::vector<PrimitiveContact> contacts;
  const Vec3 center(0.5, 0.5, 0.3);
  query.QueryCapsule(plane, center, center, 0.3, 0.02, contacts);
  std::set<int> got;
  for (const auto& c : contacts) got.insert(c.vertex);
  auto node = [](int i, int j) { return i + 11 * j; };
  EXPECT_EQ(got, (std::set<int>{node(5, 4), node(4, 5), node(5, 5), node(6, 5), node(5, 6)}));
  for (const auto& c : contacts) {
    const Vec3 p = plane.positions().col(c.vertex);
    EXPECT_NEAR(c.gap, (p - center).norm() - 0.3, 1e-15);
    EXPECT_NEAR((c.on_tool - center).norm(), 0.3, 1e-15);
  }
  EXPECT_EQ(contacts[2].vertex, node(5, 5));
  EXPECT_NEAR(contacts[2].gap, 0, 1e-15);
  EXPECT_LT((contacts[2].normal - Vec3(0, 0, -1)).norm(), 1e-15);
}

TEST(ProximityQuery, CapsuleContactsMatchTheExactDistance) {
  // A horizontal capsule (axis from x = 0.2 to 0.8 at y = 0.5, z = 0.1, radius 0.095) above a
  // plane: the contact set is every vertex whose distance to the axis segment minus the radius
  // is below the thickness, computed here independently per vertex.
  CollisionSurface plane = Sheet(20, 1.0, Vec3::Zero());
  plane.Update(2.0, false);
  const Vec3 p0(0.2, 0.5, 0.1), p1(0.8, 0.5, 0.1);
  const double radius = 0.095, thickness = 0.02;
  ProximityQuery query;
  std::vector<PrimitiveContact> contacts;
  query.QueryCapsule(plane, p0, p1, radius, thickness, contacts);
  std::vector<int> want;
  for (Index v = 0; v < plane.num_vertices(); ++v) {
    const Vec3 x = plane.positions().col(v);
    const double s = std::clamp(x.x(), 0.2, 0.8);
    const double gap = (x - Vec3(s, 0.5, 0.1)).norm() - radius;
    if (gap < thickness) want.push_back(int(v));
  }
  ASSERT_EQ(contacts.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_EQ(contacts[i].vertex, want[i]);
  // Along the axis: x = 0.2 … 0.8 (13 columns) at y = 0.45, 0.5, 0.55 (gap sqrt(0.05² + 0.1²)
  // − 0.095 = 0.017 off the axis line); beyond the ends only (0.15, 0.5) and (0.85, 0.5) (gap
  // 0.017 too; with y = 0.45 it is 0.027).
  EXPECT_EQ(want.size(), 13u * 3u + 2u);
}

TEST(ProximityQuery, BoxesAtAKnownGapTouchOnTheOverlapOfTheirFaces) {
  // Box B hovers 0.004 above box A's top face, shifted by half a cell in x. Thickness 0.01.
  // Vertices of B's bottom face above A's top face (x in [0.5, 1] of B's range [0.5, 1.5]: 3 of
  // 5 columns, all 5 rows) touch A at distance exactly 0.004; likewise A's top vertices under
  // B (x in [0.5, 1]: 3 columns × 5 rows). Boxes are 4 cells wide (cell 0.25).
  CollisionSurface a = BoxSurface(Vec3(0, 0, 0), Vec3(1, 1, 1), 4);
  CollisionSurface b = BoxSurface(Vec3(0.5, 0, 1.004), Vec3(1.5, 1, 2.004), 4);
  a.Update(2.0, false);
  b.Update(2.0, false);
  ProximityQuery query;
  ProximityResult got, want;
  query.Query(a, b, 0.01, true, got);
  BruteForceProximity(a, b, 0.01, true, false, want);
  ExpectSameContacts(got, want);
  ASSERT_EQ(got.a_on_b.size(), 15u);
  ASSERT_EQ(got.b_on_a.size(), 15u);
  for (const auto& c : got.a_on_b) {
    EXPECT_NEAR(c.distance, 0.004, 1e-12);
    EXPECT_DOUBLE_EQ(a.positions()(2, c.vertex), 1.0);
    EXPECT_GE(a.positions()(0, c.vertex), 0.5);
  }
  for (const auto& c : got.b_on_a) {
    EXPECT_NEAR(c.distance, 0.004, 1e-12);
    EXPECT_LE(b.positions()(0, c.vertex), 1.0);
  }
  // Edge–edge: the faces' edges cross each other in the overlap; all at the gap distance.
  for (const auto& e : got.edges) EXPECT_NEAR(e.distance, 0.004, 1e-12);
}

TEST(ProximityQuery, DeformingSheetsMatchBruteForce) {
  CollisionSurface a = Sheet(24, 1.0, Vec3::Zero());
  CollisionSurface b = Sheet(17, 1.0, Vec3(0.013, -0.021, 0));
  ProximityQuery query;
  ProximityResult got, want;
  std::size_t total = 0;
  for (int step = 0; step < 6; ++step) {
    Deform(a, 0.05, 0.3 * step);
    Deform(b, 0.04, -0.5 * step + 1);
    a.Update(1.5, false);
    b.Update(1.5, false);
    query.Query(a, b, 0.02, true, got);
    BruteForceProximity(a, b, 0.02, true, false, want);
    ExpectSameContacts(got, want);
    total += got.size();
  }
  EXPECT_GT(total, 100u);  // the test exercises real contacts
}

TEST(ProximityQuery, RebuildsWhenRefitDegradesAndStaysExact) {
  CollisionSurface a = Sheet(20, 1.0, Vec3::Zero());
  CollisionSurface b = Sheet(20, 1.0, Vec3(0, 0, 0.01));
  a.Update(1.5, false);
  b.Update(1.5, false);
  // Scramble a's vertices in the plane (a large deformation that ruins the old tree's boxes).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (Index v = 0; v < a.num_vertices(); ++v) a.positions().col(v) << u(rng), u(rng), 0;
  a.Update(1.5, false);
  EXPECT_EQ(a.tree().num_builds(), 2);
  EXPECT_NEAR(a.tree().quality_ratio(), 1, 1e-12);
  ProximityQuery query;
  ProximityResult got, want;
  query.Query(a, b, 0.015, true, got);
  BruteForceProximity(a, b, 0.015, true, false, want);
  ExpectSameContacts(got, want);
  EXPECT_GT(got.size(), 0u);
}

// A sheet folded over itself: the upper flap lies `gap` above the lower one.
CollisionSurface FoldedSheet(int n, double gap) {
  CollisionSurface s = Sheet(n, 2.0, Vec3::Zero());
  Points& x = s.positions();
  const double r = gap / 2;
  for (Index v = 0; v < x.cols(); ++v) {
    const double u = x(0, v);  // 0..2; fold around x = 1 with a half-cylinder of radius r
    const double bend = 1.0, arc = std::numbers::pi * r;
    if (u <= bend) continue;
    if (u <= bend + arc) {
      const double th = (u - bend) / r;
      x(0, v) = bend + r * std::sin(th);
      x(2, v) = r - r * std::cos(th);
    } else {
      x(0, v) = bend - (u - bend - arc);
      x(2, v) = gap;
    }
  }
  return s;
}

TEST(ProximityQuery, SelfCollisionOfAFoldedSheetMatchesBruteForce) {
  CollisionSurface s = FoldedSheet(30, 0.03);
  s.Update(1.5, true);
  ProximityQuery query;
  ProximityResult got, want;
  query.QuerySelf(s, 0.05, true, got);
  BruteForceProximity(s, s, 0.05, true, true, want);
  ExpectSameContacts(got, want);
  EXPECT_GT(got.a_on_b.size(), 100u);
  // The flat, unfolded sheet never touches itself.
  CollisionSurface flat = Sheet(30, 2.0, Vec3::Zero());
  flat.Update(1.5, true);
  query.QuerySelf(flat, 0.05, true, got);
  EXPECT_EQ(got.size(), 0u);
}

TEST(ProximityQuery, NoMissedContactWhenAToolMovesLessThanTheThicknessPerStep) {
  // A sphere sweeps down through a sheet in steps of 0.8 × thickness. Whenever a vertex is
  // inside the sphere after a step, it must have been reported as a contact (gap < thickness)
  // the step before: no vertex tunnels in unseen.
  CollisionSurface sheet = Sheet(40, 1.0, Vec3::Zero());
  sheet.Update(1.5, false);
  const double radius = 0.2, thickness = 0.01, step = 0.8 * thickness;
  ProximityQuery query;
  std::vector<PrimitiveContact> before, now;
  Vec3 center(0.43, 0.51, radius + 0.05);
  query.QueryCapsule(sheet, center, center, radius, thickness, before);
  int inside_checks = 0;
  for (int k = 0; k < 80; ++k) {
    center += Vec3(0.3 * step, 0, -step);
    query.QueryCapsule(sheet, center, center, radius, thickness, now);
    std::set<int> seen;
    for (const auto& c : before) seen.insert(c.vertex);
    for (Index v = 0; v < sheet.num_vertices(); ++v) {
      if ((Vec3(sheet.positions().col(v)) - center).norm() < radius) {
        ++inside_checks;
        ASSERT_TRUE(seen.count(int(v))) << "vertex " << v << " entered unseen at step " << k;
      }
    }
    // And the query is exact: every vertex within the thickness, nothing else.
    std::size_t expected = 0;
    for (Index v = 0; v < sheet.num_vertices(); ++v)
      expected += (Vec3(sheet.positions().col(v)) - center).norm() - radius < thickness;
    EXPECT_EQ(now.size(), expected);
    std::swap(before, now);
  }
  EXPECT_GT(inside_checks, 100);
}

TEST(ProximityQuery, OutputIsDeterministic) {
  CollisionSurface a = Sheet(16, 1.0, Vec3::Zero());
  CollisionSurface b = Sheet(13, 1.0, Vec3(0.01, 0.02, 0));
  Deform(a, 0.05, 0.1);
  Deform(b, 0.05, 2.0);
  a.Update(1.5, false);
  b.Update(1.5, false);
  ProximityQuery q1, q2;
  ProximityResult r1, r2;
  q1.Query(a, b, 0.03, true, r1);
  q2.Query(a, b, 0.03, true, r2);
  ExpectSameContacts(r1, r2);
  for (std::size_t i = 1; i < r1.a_on_b.size(); ++i)
    EXPECT_LT(r1.a_on_b[i - 1].vertex, r1.a_on_b[i].vertex);
}

}  // namespace
}  // namespace gipsi
