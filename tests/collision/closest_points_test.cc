#include "gipsi/collision/closest_points.h"

#include <random>

#include <gtest/gtest.h>

namespace gipsi {
namespace {

Vec3 RandomVec(std::mt19937& rng, double scale = 1) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(rng), u(rng), u(rng)};
}

// Independent reference: project onto the plane; if the projection is inside, that is the
// closest point; otherwise the closest point lies on one of the three edges.
double ReferencePointTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a).normalized();
  const Vec3 q = p - n.dot(p - a) * n;
  Eigen::Matrix<double, 3, 2> E;
  E << b - a, c - a;
  const Eigen::Vector2d st = (E.transpose() * E).ldlt().solve(E.transpose() * (q - a));
  if (st.minCoeff() >= 0 && st.sum() <= 1) return (p - q).norm();
  double best = 1e300;
  for (auto [u, v] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}})
    best = std::min(best, (p - (u + ClosestParameterOnSegment(p, u, v) * (v - u))).norm());
  return best;
}

TEST(ClosestPointOnTriangle, MatchesProjectionOrEdgeReference) {
  std::mt19937 rng(7);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 a = RandomVec(rng), b = RandomVec(rng), c = RandomVec(rng);
    const Vec3 p = RandomVec(rng, 2);
    const PointTriangleResult r = ClosestPointOnTriangle(p, a, b, c);
    // Two exact algorithms in double precision on O(1) data: 1e-12 covers their round-off.
    ASSERT_NEAR(r.distance, ReferencePointTriangle(p, a, b, c), 1e-12) << i;
    EXPECT_NEAR(r.bary.sum(), 1, 1e-14);
    EXPECT_GE(r.bary.minCoeff(), -1e-15);
    EXPECT_LT((r.bary[0] * a + r.bary[1] * b + r.bary[2] * c - r.point).norm(), 1e-14);
  }
}

TEST(ClosestPointOnTriangle, ReportsTheFeature) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(ClosestPointOnTriangle({0.2, 0.2, 1}, a, b, c).feature, TriangleFeature::kFace);
  EXPECT_EQ(ClosestPointOnTriangle({0.5, -1, 0}, a, b, c).feature, TriangleFeature::kEdge01);
  EXPECT_EQ(ClosestPointOnTriangle({1, 1, 0}, a, b, c).feature, TriangleFeature::kEdge12);
  EXPECT_EQ(ClosestPointOnTriangle({-1, 0.5, 0}, a, b, c).feature, TriangleFeature::kEdge20);
  EXPECT_EQ(ClosestPointOnTriangle({-1, -1, 0}, a, b, c).feature, TriangleFeature::kVertex0);
  EXPECT_EQ(ClosestPointOnTriangle({2, -0.5, 0}, a, b, c).feature, TriangleFeature::kVertex1);
  EXPECT_EQ(ClosestPointOnTriangle({-0.5, 2, 0}, a, b, c).feature, TriangleFeature::kVertex2);
  const PointTriangleResult face = ClosestPointOnTriangle({0.2, 0.3, -2}, a, b, c);
  EXPECT_DOUBLE_EQ(face.distance, 2);
  EXPECT_LT((face.point - Vec3(0.2, 0.3, 0)).norm(), 1e-15);
}

TEST(ClosestPointOnTriangle, HandlesDegenerateTriangles) {
  // Collinear vertices: the closest point is on the segment they span.
  const PointTriangleResult r =
      ClosestPointOnTriangle({0.5, 1, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0});
  EXPECT_DOUBLE_EQ(r.distance, 1);
  EXPECT_NEAR(r.bary.sum(), 1, 1e-15);
}

// Reference: the unconstrained minimiser if it is inside the unit square, else the best of the
// four point–segment distances from the end points (the minimum lies on the square's border).
double ReferenceSegments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  Eigen::Matrix2d A;
  A << d1.dot(d1), -d1.dot(d2), -d1.dot(d2), d2.dot(d2);
  const Eigen::Vector2d st = A.fullPivLu().solve(Eigen::Vector2d(-d1.dot(r), d2.dot(r)));
  if (std::abs(A.determinant()) > 1e-12 && st.minCoeff() >= 0 && st.maxCoeff() <= 1)
    return (p0 + st[0] * d1 - q0 - st[1] * d2).norm();
  auto ps = [](const Vec3& p, const Vec3& a, const Vec3& b) {
    return (p - (a + ClosestParameterOnSegment(p, a, b) * (b - a))).norm();
  };
  return std::min({ps(p0, q0, q1), ps(p1, q0, q1), ps(q0, p0, p1), ps(q1, p0, p1)});
}

TEST(ClosestPointsOfSegments, MatchesReference) {
  std::mt19937 rng(11);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p0 = RandomVec(rng), p1 = RandomVec(rng), q0 = RandomVec(rng), q1 = RandomVec(rng);
    const SegmentSegmentResult r = ClosestPointsOfSegments(p0, p1, q0, q1);
    ASSERT_NEAR(r.distance, ReferenceSegments(p0, p1, q0, q1), 1e-12) << i;
    EXPECT_LT((r.on_p - (p0 + r.s * (p1 - p0))).norm(), 1e-14);
    EXPECT_LT((r.on_q - (q0 + r.t * (q1 - q0))).norm(), 1e-14);
  }
}

TEST(ClosestPointsOfSegments, CrossingAndParallelCases) {
  const SegmentSegmentResult cross =
      ClosestPointsOfSegments({-1, 0, 0}, {1, 0, 0}, {0, -1, 0.5}, {0, 1, 0.5});
  EXPECT_DOUBLE_EQ(cross.distance, 0.5);
  EXPECT_DOUBLE_EQ(cross.s, 0.5);
  EXPECT_DOUBLE_EQ(cross.t, 0.5);
  EXPECT_FALSE(cross.parallel);
  const SegmentSegmentResult par =
      ClosestPointsOfSegments({0, 0, 0}, {1, 0, 0}, {0.5, 0.25, 0}, {2, 0.25, 0});
  EXPECT_TRUE(par.parallel);
  EXPECT_DOUBLE_EQ(par.distance, 0.25);
}

}  // namespace
}  // namespace gipsi
