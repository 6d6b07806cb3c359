#include "gipsi/geometry/quality.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gipsi/geometry/generators.h"

namespace gipsi {
namespace {

using ::testing::ElementsAre;
using ::testing::IsEmpty;

/// The regular tetrahedron with edge length 2·sqrt(2) (alternate corners of a cube).
void RegularTet(Points& nodes, Tets& tets) {
  nodes.resize(3, 4);
  nodes << 1, 1, -1, -1,  //
      1, -1, 1, -1,       //
      1, -1, -1, 1;
  tets.resize(4, 1);
  tets << 0, 1, 2, 3;
  if (TetSignedVolume(nodes.col(0), nodes.col(1), nodes.col(2), nodes.col(3)) < 0)
    std::swap(tets(2, 0), tets(3, 0));
}

TEST(TetSignedVolume, IsOneSixthForTheRightHandedUnitTet) {
  EXPECT_DOUBLE_EQ(TetSignedVolume(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)),
                   1.0 / 6);
  EXPECT_DOUBLE_EQ(TetSignedVolume(Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(0, 0, 1)),
                   -1.0 / 6);
}

TEST(TetQuality, RegularTetHasAspectOne) {
  Points nodes;
  Tets tets;
  RegularTet(nodes, tets);
  const TetQualityReport report = CheckTetQuality(nodes, tets);
  EXPECT_EQ(report.num_tets, 1);
  EXPECT_NEAR(report.min_aspect, 1, 1e-14);
  EXPECT_NEAR(report.max_aspect, 1, 1e-14);
  EXPECT_NEAR(report.mean_aspect, 1, 1e-14);
  EXPECT_EQ(report.worst_aspect_tet, 0);
  EXPECT_NEAR(report.total_volume, 8.0 / 3, 1e-14);  // cube 8 minus four corners of 4/3
  EXPECT_THAT(report.inverted, IsEmpty());
  EXPECT_THAT(report.degenerate, IsEmpty());
}

TEST(TetQuality, AspectGrowsAsATetFlattens) {
  Points nodes;
  Tets tets;
  RegularTet(nodes, tets);
  double previous = 1;
  for (double squash : {0.5, 0.1, 0.01}) {
    Points flat = nodes;
    flat.row(2) *= squash;
    const double aspect = CheckTetQuality(flat, tets).max_aspect;
    EXPECT_GT(aspect, previous);
    previous = aspect;
  }
}

TEST(TetQuality, FlagsAnInvertedTetById) {
  Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(2, 1, 1), {2, 1, 1});
  std::swap(box.tets(0, 7), box.tets(1, 7));
  const TetQualityReport report = CheckTetQuality(box.nodes, box.tets);
  EXPECT_THAT(report.inverted, ElementsAre(7));
  EXPECT_THAT(report.degenerate, IsEmpty());
  EXPECT_NEAR(report.min_volume, -1.0 / 6, 1e-15);
  EXPECT_NEAR(report.total_volume, 2 - 2.0 / 6, 1e-14);
}

TEST(TetQuality, FlagsAFlatTetAsDegenerateById) {
  Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 1, 1});
  // Tet 3 made of four corners of the face z = 0.
  box.tets.col(3) << 0, 1, 3, 2;
  const TetQualityReport report = CheckTetQuality(box.nodes, box.tets);
  EXPECT_THAT(report.degenerate, ElementsAre(3));
  EXPECT_THAT(report.inverted, IsEmpty());
  EXPECT_NE(report.worst_aspect_tet, 3);  // aspect statistics skip degenerate tets
  EXPECT_TRUE(std::isfinite(report.max_aspect));
}

TEST(TetQuality, EmptyMeshGivesAnEmptyReport) {
  const TetQualityReport report = CheckTetQuality(Points(3, 0), Tets(4, 0));
  EXPECT_EQ(report.num_tets, 0);
  EXPECT_EQ(report.worst_aspect_tet, -1);
  EXPECT_EQ(report.total_volume, 0);
}

}  // namespace
}  // namespace gipsi
