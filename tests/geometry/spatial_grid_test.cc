#include "gipsi/geometry/spatial_grid.h"

#include <limits>
#include <random>
#include <set>

#include <gtest/gtest.h>

namespace gipsi {
namespace {

Points RandomPoints(Index count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Points p(3, count);
  for (Index j = 0; j < count; ++j) p.col(j) = Vec3(u(rng), u(rng), u(rng));
  return p;
}

/// Nearest search by the grid equals brute force, for point sets of any dimension.
void ExpectNearestMatchesBruteForce(const Points& sources, const Points& queries) {
  const SpatialGrid grid(sources, sources);
  for (Index q = 0; q < queries.cols(); ++q) {
    const Vec3 p = queries.col(q);
    double distance = 0;
    const int found = grid.FindNearest(
        p, [&](int s) { return (sources.col(s) - p).norm(); }, distance);
    ASSERT_GE(found, 0);
    EXPECT_DOUBLE_EQ(distance, (sources.colwise() - p).colwise().norm().minCoeff());
    EXPECT_DOUBLE_EQ((sources.col(found) - p).norm(), distance);
  }
}

TEST(SpatialGrid, NearestMatchesBruteForceInVolumesPlanesLinesAndPoints) {
  const Points queries = 3 * RandomPoints(200, 1);
  Points volume = RandomPoints(500, 2);
  ExpectNearestMatchesBruteForce(volume, queries);
  Points plane = volume;
  plane.row(2).setConstant(0.25);
  ExpectNearestMatchesBruteForce(plane, queries);
  Points line = plane;
  line.row(1).setZero();
  ExpectNearestMatchesBruteForce(line, queries);
  ExpectNearestMatchesBruteForce(Points::Constant(3, 4, 0.5), queries);
}

// Points halfway between neighbours of a regular lattice are as far from both: the lower index
// is found. (A tie across rings, where the search once stopped a ring early, is met by the parts'
// grids of SplitCoupling.ANearestCopyJoinsObjectsSplitAnyWay on 4 ranks.)
TEST(SpatialGrid, NearestTakesTheLowestIndexOnATie) {
  Points lattice(3, 21 * 9 * 5);  // a 10 × 4 × 2 box's nodes every 0.5
  for (Index k = 0; k < lattice.cols(); ++k)
    lattice.col(k) = 0.5 * Vec3(k % 21, (k / 21) % 9, k / (21 * 9));
  const SpatialGrid grid(lattice, lattice);
  int ties = 0;
  for (Index k = 0; k + 1 < lattice.cols(); ++k) {
    const Vec3 p = 0.5 * (lattice.col(k) + lattice.col(k + 1));
    Index lowest = 0;
    double best = std::numeric_limits<double>::infinity();
    for (Index s = 0; s < lattice.cols(); ++s)
      if ((lattice.col(s) - p).norm() < best) {
        best = (lattice.col(s) - p).norm();
        lowest = s;
      }
    ties += (lattice.col(k) - p).norm() == (lattice.col(k + 1) - p).norm();
    double distance = 0;
    ASSERT_EQ(grid.FindNearest(
                  p, [&](int s) { return (lattice.col(s) - p).norm(); }, distance),
              lowest)
        << "halfway between " << k << " and " << k + 1;
    EXPECT_EQ(distance, best);
  }
  EXPECT_GT(ties, 400);
}

TEST(SpatialGrid, CellVisitsEveryBoxContainingThePoint) {
  const Points centers = RandomPoints(400, 3);
  const Points half = 0.1 * (RandomPoints(400, 4).array().abs() + 0.1).matrix();
  const Points lo = centers - half, hi = centers + half;
  const SpatialGrid grid(lo, hi);
  const Points queries = RandomPoints(300, 5);
  for (Index q = 0; q < queries.cols(); ++q) {
    const Vec3 p = queries.col(q);
    std::set<int> visited;
    grid.ForEachInCell(p, [&](int item) { visited.insert(item); });
    for (Index k = 0; k < lo.cols(); ++k) {
      if ((p.array() >= lo.col(k).array()).all() && (p.array() <= hi.col(k).array()).all()) {
        EXPECT_EQ(visited.count(int(k)), 1u) << "query " << q << " box " << k;
      }
    }
  }
}

TEST(SpatialGrid, EmptyGridFindsNothing) {
  const SpatialGrid grid(Points(3, 0), Points(3, 0));
  double distance = 0;
  EXPECT_EQ(grid.FindNearest(
                Vec3::Zero(), [](int) { return 0.0; }, distance),
            -1);
  int visits = 0;
  grid.ForEachInCell(Vec3::Zero(), [&](int) { ++visits; });
  EXPECT_EQ(visits, 0);
}

}  // namespace
}  // namespace gipsi
