#include "gipsi/geometry/normals.h"

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/generators.h"

namespace gipsi {
namespace {

TEST(TriangleAreas, AreHalfTheCrossProductLength) {
  Points x(3, 4);
  x << 0, 2, 0, 1,  //
      0, 0, 3, 1,   //
      0, 0, 0, 0;
  Triangles tri(3, 2);
  tri << 0, 0,  //
      1, 1,     //
      2, 3;
  const VecX areas = TriangleAreas(x, tri);
  EXPECT_DOUBLE_EQ(areas[0], 3);
  EXPECT_DOUBLE_EQ(areas[1], 1);
}

TEST(FaceNormals, FollowTheRightHandRuleAndAreZeroWhenDegenerate) {
  Points x(3, 4);
  x << 0, 1, 0, 2,  //
      0, 0, 1, 0,   //
      0, 0, 0, 0;
  Triangles tri(3, 3);
  tri << 0, 0, 0,  //
      1, 2, 1,     //
      2, 1, 3;     // the third is collinear
  const Points n = FaceNormals(x, tri);
  EXPECT_EQ(n.col(0), Vec3(0, 0, 1));
  EXPECT_EQ(n.col(1), Vec3(0, 0, -1));
  EXPECT_EQ(n.col(2), Vec3::Zero());
}

/// The boundary of a cube [-1,1]³ pushed onto the unit sphere: a closed, outward, sphere-like
/// surface.
void SphereLikeSurface(Points& x, Triangles& tri) {
  const Mesh cube = MakeTetBox(Vec3(-1, -1, -1), Vec3(1, 1, 1), {4, 4, 4});
  const BoundarySurface boundary = MakeBoundary(cube);
  boundary.Gather(cube.nodes, x);
  x.colwise().normalize();
  tri = boundary.triangles;
}

TEST(VertexNormals, PointOutwardOnASphereLikeSurface) {
  Points x;
  Triangles tri;
  SphereLikeSurface(x, tri);
  Points normals;
  VertexNormals(x, tri, normals);
  ASSERT_EQ(normals.cols(), x.cols());
  for (Index v = 0; v < x.cols(); ++v) {
    EXPECT_NEAR(normals.col(v).norm(), 1, 1e-12);
    // On a sphere the outward normal is the position; the faceting tilts it a little.
    EXPECT_GT(normals.col(v).dot(x.col(v)), 0.95) << "vertex " << v;
  }
}

TEST(VertexNormals, AreAreaWeighted) {
  // Two triangles at a shared vertex: a large one in z=0 and a small one in x=0.
  Points x(3, 5);
  x << 0, 2, 0, 0, 0,   //
      0, 0, 2, 0, 0.1,  //
      0, 0, 0, 0.1, 0;
  Triangles tri(3, 2);
  tri << 0, 0,  //
      1, 3,     //
      2, 4;
  Points normals;
  VertexNormals(x, tri, normals);
  // Areas 2 (normal +z) and 0.005 (normal −x) weigh the normal at vertex 0.
  const Vec3 n_small = (x.col(3) - x.col(0)).cross(x.col(4) - x.col(0)).normalized();
  const Vec3 expected = (2 * Vec3(0, 0, 1) + 0.005 * n_small).normalized();
  EXPECT_NEAR((normals.col(0) - expected).norm(), 0, 1e-14);
}

TEST(VertexNormals, GiveZeroForUnusedVerticesAndKeepSizedOutputStorage) {
  Points x;
  Triangles tri;
  SphereLikeSurface(x, tri);
  Points extended(3, x.cols() + 1);
  extended << x, Vec3(3, 3, 3);
  Points normals(3, extended.cols());
  const double* storage = normals.data();
  VertexNormals(extended, tri, normals);
  EXPECT_EQ(normals.data(), storage);
  EXPECT_EQ(normals.col(x.cols()), Vec3::Zero());
}

}  // namespace
}  // namespace gipsi
