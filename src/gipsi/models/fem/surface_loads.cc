#include "gipsi/models/fem/surface_loads.h"

#include "gipsi/models/fem/fem_geometry.h"

namespace gipsi {

void AreaNormalDerivatives(const Vec3& x0, const Vec3& x1, const Vec3& x2, Mat3 out[3]) {
  const Vec3 e1 = x1 - x0, e2 = x2 - x0;
  out[1] = -CrossMatrix(e2);
  out[2] = CrossMatrix(e1);
  out[0] = -(out[1] + out[2]);
}

void FaceLoads(const Vec3& x0, const Vec3& x1, const Vec3& x2, double p, const Vec3& t, Vec3& f0,
               Vec3& f1, Vec3& f2) {
  const Vec3 n2 = (x1 - x0).cross(x2 - x0);
  const Vec3 load = (-p / 6.0) * n2 + (n2.norm() / 6.0) * t;
  f0 += load;
  f1 += load;
  f2 += load;
}

Mat99 FaceLoadJacobian(const Vec3& x0, const Vec3& x1, const Vec3& x2, double p, const Vec3& t) {
  Mat3 dn[3];
  AreaNormalDerivatives(x0, x1, x2, dn);
  const Vec3 n2 = (x1 - x0).cross(x2 - x0);
  const double len = n2.norm();
  Mat99 jac;
  for (int b = 0; b < 3; ++b) {
    Mat3 block = (-p / 6.0) * dn[b];
    if (len > 0 && t.squaredNorm() > 0) block += t * (n2.transpose() * dn[b]) / (6.0 * len);
    for (int a = 0; a < 3; ++a) jac.block<3, 3>(3 * a, 3 * b) = block;
  }
  return jac;
}

}  // namespace gipsi
