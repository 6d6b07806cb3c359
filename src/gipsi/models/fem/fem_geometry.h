#pragma once
/// @file
/// Small geometric helpers shared by the solid objects (FemSolid, MixedSolid) and their loads.

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Orthonormal material axes as columns (fibre f, sheet s, sheet-normal n = f × s): f is the
/// normalised `fibre` (non-zero), s the part of `sheet` orthogonal to it, normalised (any unit
/// vector orthogonal to f when `sheet` is nearly parallel to it).
inline Mat3 MaterialAxes(const Vec3& fibre, const Vec3& sheet) {
  Mat3 axes;
  const Vec3 f = fibre.normalized();
  Vec3 s = sheet - sheet.dot(f) * f;
  if (s.norm() < 1e-8) s = f.unitOrthogonal();
  s.normalize();
  axes.col(0) = f;
  axes.col(1) = s;
  axes.col(2) = f.cross(s);
  return axes;
}

/// The cross-product matrix [u]×, with [u]× v = u × v.
inline Mat3 CrossMatrix(const Vec3& u) {
  Mat3 m;
  m << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
  return m;
}

}  // namespace gipsi
GIPSI_EXPORT_END
