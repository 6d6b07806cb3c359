#include "gipsi/geometry/mapping.h"

#include <algorithm>
#include <limits>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/quality.h"

namespace gipsi {
namespace {

using ::testing::StrEq;
using ::testing::ThrowsMessage;

/// A box [0,3]×[0,2]×[0,2] of 6×5×4 cells with interior nodes jittered (by up to 0.1 cell),
/// so that the tets are irregular.
Mesh JitteredBox() {
  Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(3, 2, 2), {6, 5, 4});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.04, 0.04);
  for (Index n = 0; n < box.num_nodes(); ++n) {
    const Vec3 x = box.nodes.col(n);
    if ((x.array() > 0).all() && (x.array() < Vec3(3, 2, 2).array()).all())
      box.nodes.col(n) += Vec3(jitter(rng), jitter(rng), jitter(rng));
  }
  return box;
}

Points RandomPoints(Index count, const Vec3& lo, const Vec3& hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  Points p(3, count);
  for (Index j = 0; j < count; ++j)
    for (int a = 0; a < 3; ++a) p(a, j) = lo[a] + u(rng) * (hi[a] - lo[a]);
  return p;
}

/// Reference distance from p to segment [a, b].
double SegmentDistance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return (a + t * (b - a) - p).norm();
}

/// Reference distance from p to triangle (a, b, c): the plane if the projection is inside,
/// else the closest edge.
double TriangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a).normalized();
  const Vec3 q = p - n.dot(p - a) * n;
  const bool inside = (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
                      (a - c).cross(q - c).dot(n) >= 0;
  if (inside) return std::abs(n.dot(p - a));
  return std::min({SegmentDistance(p, a, b), SegmentDistance(p, b, c), SegmentDistance(p, c, a)});
}

double SurfaceDistance(const Vec3& p, const Points& x, const Triangles& tri) {
  double best = std::numeric_limits<double>::infinity();
  for (Index t = 0; t < tri.cols(); ++t)
    best =
        std::min(best, TriangleDistance(p, x.col(tri(0, t)), x.col(tri(1, t)), x.col(tri(2, t))));
  return best;
}

Points Reproduce(const PointMap& map, const Points& source) {
  Points out(3, map.num_targets());
  map.Apply(source, out);
  return out;
}

// Target 0 blends items 0 and 1 (weights 0.5, 0.5), target 1 items 1 and 2 with item 2 at zero
// weight. A marked item (-1) with weight makes the target read -1, per component; one with zero
// weight does not matter; unmarked components blend as Apply does.
TEST(PointMap, ApplyMarkedNeverBlendsTheMarker) {
  Eigen::Matrix4Xi indices(4, 2);
  indices << 0, 1,  //
      1, 2,         //
      0, 1,         //
      0, 1;
  Eigen::Matrix4Xd weights(4, 2);
  weights << 0.5, 1,  //
      0.5, 0,         //
      0, 0,           //
      0, 0;
  const PointMap map = PointMap::FromWeights(indices, weights, 0);
  Eigen::MatrixXd source(2, 3);
  source << 10, -1, -1,  //
      10, 20, 30;
  Eigen::MatrixXd out(2, 2), plain(2, 2);
  map.ApplyMarked(source, out, -1);
  map.Apply(source, plain);
  EXPECT_EQ(out(0, 0), -1);  // 0.5 * 10 + 0.5 * (-1) = 4.5 before
  EXPECT_EQ(plain(0, 0), 4.5);
  EXPECT_EQ(out(0, 1), -1);  // item 1 alone
  EXPECT_EQ(out(1, 0), 15);  // the unmarked component blends
  EXPECT_EQ(out(1, 1), 20);  // item 2 (marked in row 0, weight 0) does not matter
}

TEST(PointMap, BarycentricInTetsReproducesLinearFieldsInside) {
  const Mesh box = JitteredBox();
  ASSERT_TRUE(CheckTetQuality(box.nodes, box.tets).inverted.empty());
  const Points targets = RandomPoints(3000, Vec3(0.05, 0.05, 0.05), Vec3(2.95, 1.95, 1.95), 1);
  const PointMap map = PointMap::BarycentricInTets(box.nodes, box.tets, targets);
  ASSERT_EQ(map.num_targets(), targets.cols());
  // The coordinates themselves are a linear field.
  EXPECT_LT((Reproduce(map, box.nodes) - targets).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(map.max_distance(), 1e-12);
  // So is any affine field f(x) = A x + b, here with 2 components.
  Eigen::Matrix<double, 2, 3> A;
  A << 1, -2, 0.5, 3, 0, -1;
  const Eigen::Vector2d b(0.25, -4);
  const Eigen::MatrixXd f_nodes = (A * box.nodes).colwise() + b;
  Eigen::MatrixXd f_targets(2, targets.cols());
  map.Apply(f_nodes, f_targets);
  const Eigen::MatrixXd expected = (A * targets).colwise() + b;
  EXPECT_LT((f_targets - expected).cwiseAbs().maxCoeff(), 1e-12);
  for (Index j = 0; j < targets.cols(); ++j) {
    EXPECT_NEAR(map.weights().col(j).sum(), 1, 1e-13);
    EXPECT_GE(map.weights().col(j).minCoeff(), -1e-12);
  }
}

TEST(PointMap, BarycentricInTetsReproducesNodesAndHandlesNegativeTets) {
  Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2});
  box.tets.row(2).swap(box.tets.row(3));  // every tet negatively oriented
  const PointMap map = PointMap::BarycentricInTets(box.nodes, box.tets, box.nodes);
  EXPECT_LT((Reproduce(map, box.nodes) - box.nodes).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(PointMap, BarycentricInTetsClampsOutsideTargetsToTheNearestTet) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {3, 3, 3});
  Points targets(3, 3);
  targets << 1.5, 0.3, 2,  //
      0.4, 0.6, 2,         //
      0.7, -0.2, 2;
  const PointMap map = PointMap::BarycentricInTets(box.nodes, box.tets, targets);
  const Points at = Reproduce(map, box.nodes);
  EXPECT_LT((at.col(0) - Vec3(1, 0.4, 0.7)).norm(), 1e-14);
  EXPECT_LT((at.col(1) - Vec3(0.3, 0.6, 0)).norm(), 1e-14);
  EXPECT_LT((at.col(2) - Vec3(1, 1, 1)).norm(), 1e-14);
  EXPECT_NEAR(map.max_distance(), std::sqrt(3.0), 1e-14);
  for (Index j = 0; j < 3; ++j) {
    EXPECT_GE(map.weights().col(j).minCoeff(), 0);
    EXPECT_NEAR(map.weights().col(j).sum(), 1, 1e-14);
  }
}

TEST(PointMap, BarycentricInTetsFindsTheNearestTetForAnyOutsidePoint) {
  const Mesh box = JitteredBox();
  const BoundarySurface boundary = MakeBoundary(box);
  Points surface;
  boundary.Gather(box.nodes, surface);
  Points targets = RandomPoints(400, Vec3(-2, -2, -2), Vec3(5, 4, 4), 2);
  const PointMap map = PointMap::BarycentricInTets(box.nodes, box.tets, targets);
  const Points at = Reproduce(map, box.nodes);
  double max_gap = 0;
  for (Index j = 0; j < targets.cols(); ++j) {
    const Vec3 p = targets.col(j);
    const bool outside = p.x() < 0 || p.x() > 3 || p.y() < 0 || p.y() > 2 || p.z() < 0 || p.z() > 2;
    const double expected = outside ? SurfaceDistance(p, surface, boundary.triangles) : 0;
    EXPECT_NEAR((at.col(j) - p).norm(), expected, 1e-12) << "target " << j;
    max_gap = std::max(max_gap, expected);
  }
  EXPECT_NEAR(map.max_distance(), max_gap, 1e-12);
}

TEST(PointMap, BarycentricInTetsMeasuresOutsideDistanceOnLargeMeshes) {
  // 48,000 tets and 10,000 targets, a third of them outside. (Its speed is measured by
  // bench/mass_spring_bench.cc, BM_BarycentricBuild, not here.)
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {20, 20, 20});
  const Points targets = RandomPoints(10000, Vec3(-0.1, -0.1, -0.1), Vec3(1.1, 1.1, 1.1), 3);
  const PointMap map = PointMap::BarycentricInTets(box.nodes, box.tets, targets);
  double max_gap = 0;  // distance from each target to the box [0,1]³
  for (Index j = 0; j < targets.cols(); ++j)
    max_gap = std::max(max_gap, (targets.col(j) - targets.col(j).cwiseMax(0).cwiseMin(1)).norm());
  EXPECT_NEAR(map.max_distance(), max_gap, 1e-12);
}

TEST(PointMap, BarycentricOnTrianglesReturnsTheClosestSurfacePoint) {
  // A closed, curved surface: the boundary of a cube pushed onto the unit sphere.
  const Mesh cube = MakeTetBox(Vec3(-1, -1, -1), Vec3(1, 1, 1), {4, 4, 4});
  const BoundarySurface boundary = MakeBoundary(cube);
  Points x;
  boundary.Gather(cube.nodes, x);
  x.colwise().normalize();
  const Points targets = RandomPoints(500, Vec3(-2, -2, -2), Vec3(2, 2, 2), 4);
  const PointMap map = PointMap::BarycentricOnTriangles(x, boundary.triangles, targets);
  const Points at = Reproduce(map, x);
  double max_gap = 0;
  for (Index j = 0; j < targets.cols(); ++j) {
    const double expected = SurfaceDistance(targets.col(j), x, boundary.triangles);
    EXPECT_NEAR((at.col(j) - targets.col(j)).norm(), expected, 1e-12) << "target " << j;
    EXPECT_GE(map.weights().col(j).minCoeff(), 0);
    EXPECT_EQ(map.weights()(3, j), 0);
    max_gap = std::max(max_gap, expected);
  }
  EXPECT_NEAR(map.max_distance(), max_gap, 1e-12);
}

TEST(PointMap, BarycentricOnTrianglesProjectsOntoAFlatSheet) {
  const Mesh sheet = MakeTriangleSheet(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), {4, 4});
  Points targets(3, 2);
  targets << 0.3, 1.5,  //
      0.7, 0.25,        //
      0.2, 0;
  const PointMap map = PointMap::BarycentricOnTriangles(sheet.nodes, sheet.triangles, targets);
  const Points at = Reproduce(map, sheet.nodes);
  EXPECT_LT((at.col(0) - Vec3(0.3, 0.7, 0)).norm(), 1e-15);
  EXPECT_LT((at.col(1) - Vec3(1, 0.25, 0)).norm(), 1e-15);
  EXPECT_NEAR(map.max_distance(), 0.5, 1e-15);
}

TEST(PointMap, NearestPicksTheClosestSource) {
  const Points sources = RandomPoints(300, Vec3(0, 0, 0), Vec3(1, 2, 0.5), 5);
  const Points targets = RandomPoints(300, Vec3(-1, -1, -1), Vec3(2, 3, 1.5), 6);
  const PointMap map = PointMap::Nearest(sources, targets);
  double max_gap = 0;
  for (Index j = 0; j < targets.cols(); ++j) {
    const double expected = (sources.colwise() - targets.col(j)).colwise().norm().minCoeff();
    EXPECT_DOUBLE_EQ((sources.col(map.indices()(0, j)) - targets.col(j)).norm(), expected);
    EXPECT_EQ(map.weights().col(j), Eigen::Vector4d(1, 0, 0, 0));
    max_gap = std::max(max_gap, expected);
  }
  EXPECT_DOUBLE_EQ(map.max_distance(), max_gap);
}

TEST(PointMap, ApplyWritesEveryRowIntoTheGivenStorage) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 1, 1});
  const Points targets = RandomPoints(10, Vec3(0, 0, 0), Vec3(1, 1, 1), 8);
  const PointMap map = PointMap::BarycentricInTets(box.nodes, box.tets, targets);
  Eigen::MatrixXd values(1, box.num_nodes());
  values.row(0) = box.nodes.colwise().sum();  // f = x + y + z
  Eigen::MatrixXd out(1, targets.cols());
  const double* storage = out.data();
  map.Apply(values, out);
  EXPECT_EQ(out.data(), storage);
  for (Index j = 0; j < targets.cols(); ++j) EXPECT_NEAR(out(0, j), targets.col(j).sum(), 1e-14);
}

TEST(PointMapDeathTest, ApplyChecksShapes) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 1, 1});
  const PointMap map = PointMap::BarycentricInTets(box.nodes, box.tets, Points::Zero(3, 2));
  Eigen::MatrixXd out(3, 5);
  EXPECT_DEATH(map.Apply(box.nodes, out), "check failed: out.rows\\(\\) == source.rows\\(\\)");
  Eigen::MatrixXd out2(3, 2);
  EXPECT_DEATH(map.Apply(box.nodes.leftCols(2), out2),
               "check failed: indices_.maxCoeff\\(\\) < source.cols\\(\\)");
}

TEST(PointMap, RejectsTargetsWithoutSources) {
  const Points targets = Points::Zero(3, 2);
  EXPECT_THAT([&] { PointMap::BarycentricInTets(targets, Tets(4, 0), targets); },
              ThrowsMessage<InputError>(StrEq(
                  "barycentric embedding: cannot embed 2 points in a mesh without tetrahedra")));
  EXPECT_THAT([&] { PointMap::Nearest(Points(3, 0), targets); },
              ThrowsMessage<InputError>(
                  StrEq("nearest-point map: cannot map 2 points to an empty set of sources")));
  EXPECT_EQ(PointMap::BarycentricInTets(targets, Tets(4, 0), Points(3, 0)).num_targets(), 0);
  Points bad = targets;
  bad(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(
      [&] { PointMap::Nearest(targets, bad); },
      ThrowsMessage<InputError>(StrEq("nearest-point map: target 1 has non-finite coordinates")));
}

}  // namespace
}  // namespace gipsi
