#include "gipsi/models/fem/surface_loads.h"

#include <gtest/gtest.h>

namespace gipsi {
namespace {

TEST(FaceLoads, JacobianMatchesFiniteDifferences) {
  const Vec3 x[3] = {Vec3(0.1, 0.2, -0.3), Vec3(1.2, 0.1, 0.2), Vec3(0.3, 0.9, 0.4)};
  const double p = 1234.5;
  const Vec3 t(300, -200, 50);
  const Mat99 jac = FaceLoadJacobian(x[0], x[1], x[2], p, t);
  // Loads are quadratic in x (pressure part) and smooth (traction part): central differences
  // with h = 1e-6 m are accurate to ~1e-12 relative to the load magnitude (~1e3 N).
  const double h = 1e-6;
  for (int b = 0; b < 3; ++b)
    for (int k = 0; k < 3; ++k) {
      Vec3 xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
      xp[b][k] += h;
      xm[b][k] -= h;
      Vec3 fp[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
      Vec3 fm[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
      FaceLoads(xp[0], xp[1], xp[2], p, t, fp[0], fp[1], fp[2]);
      FaceLoads(xm[0], xm[1], xm[2], p, t, fm[0], fm[1], fm[2]);
      for (int a = 0; a < 3; ++a)
        for (int i = 0; i < 3; ++i)
          EXPECT_NEAR(jac(3 * a + i, 3 * b + k), (fp[a][i] - fm[a][i]) / (2 * h), 1e-6)
              << a << i << b << k;
    }
}

TEST(FaceLoads, PressureOnAFaceIsPressureTimesAreaAlongTheInwardNormal) {
  Vec3 f[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  FaceLoads(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 3, 0), 10.0, Vec3::Zero(), f[0], f[1], f[2]);
  // Area 3 m², outward (right-hand) normal +z, so 30 N pushes along −z, a third per vertex.
  for (const Vec3& fi : f) EXPECT_TRUE(fi.isApprox(Vec3(0, 0, -10), 1e-15));
}

}  // namespace
}  // namespace gipsi
