#include "gipsi/geometry/enclosed_volume.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/generators.h"

namespace gipsi {
namespace {

struct Surface {
  Points x;
  Triangles triangles;
};

Surface BoxSurface(const Vec3& lo, const Vec3& hi, bool drop_top) {
  const Mesh box = MakeTetBox(lo, hi, {3, 2, 4});
  const BoundarySurface b = ExtractTetBoundary(box.nodes, box.tets);
  Surface s;
  s.x.resize(3, b.num_vertices());
  for (Index v = 0; v < b.num_vertices(); ++v)
    s.x.col(v) = box.nodes.col(b.vertex_to_node[static_cast<std::size_t>(v)]);
  std::vector<int> keep;
  for (Index t = 0; t < b.num_triangles(); ++t) {
    bool top = true;
    for (int i = 0; i < 3; ++i) top = top && s.x(2, b.triangles(i, t)) == hi.z();
    if (!(drop_top && top)) keep.push_back(static_cast<int>(t));
  }
  s.triangles.resize(3, static_cast<Index>(keep.size()));
  for (std::size_t k = 0; k < keep.size(); ++k)
    s.triangles.col(static_cast<Index>(k)) = b.triangles.col(keep[k]);
  return s;
}

TEST(EnclosedVolume, ClosedBoxSurfaceGivesTheBoxVolume) {
  const Surface s = BoxSurface(Vec3(0, 0, 0), Vec3(2, 3, 0.5), false);
  EnclosedVolume volume(s.triangles, s.x.cols());
  EXPECT_EQ(volume.num_loops(), 0);
  EXPECT_NEAR(volume.Compute(s.x), 3.0, 1e-13);
}

TEST(EnclosedVolume, OpenSurfaceIsCappedAtItsRim) {
  // Without its top the box is open; the cap over the planar rim restores the full volume,
  // wherever the box sits (the cap moves with the rim).
  for (const Vec3& shift : {Vec3(0, 0, 0), Vec3(5, -7, 11)}) {
    const Surface s = BoxSurface(shift, shift + Vec3(2, 3, 0.5), true);
    EnclosedVolume volume(s.triangles, s.x.cols());
    EXPECT_EQ(volume.num_loops(), 1);
    EXPECT_NEAR(volume.Compute(s.x), 3.0, 1e-12);
  }
}

TEST(EnclosedVolume, GradientMatchesFiniteDifferences) {
  Surface s = BoxSurface(Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  s.x += 0.05 * Points::Random(3, s.x.cols());  // a wobbly open cup
  EnclosedVolume volume(s.triangles, s.x.cols());
  Points grad;
  volume.Compute(s.x, &grad);
  // V is a cubic polynomial in x: central differences are exact up to h² times the third
  // derivative (~1) plus round-off ~1e-16/h; h = 1e-5 gives ~1e-10.
  const double h = 1e-5;
  for (Index v = 0; v < s.x.cols(); ++v)
    for (int a = 0; a < 3; ++a) {
      Points xp = s.x, xm = s.x;
      xp(a, v) += h;
      xm(a, v) -= h;
      const double fd = (volume.Compute(xp) - volume.Compute(xm)) / (2 * h);
      EXPECT_NEAR(grad(a, v), fd, 1e-9) << "vertex " << v << " axis " << a;
    }
}

TEST(EnclosedVolume, RejectsInconsistentOrientation) {
  Surface s = BoxSurface(Vec3(0, 0, 0), Vec3(1, 1, 1), false);
  std::swap(s.triangles(1, 0), s.triangles(2, 0));
  EXPECT_THROW(EnclosedVolume(s.triangles, s.x.cols()), InputError);
}

}  // namespace
}  // namespace gipsi
