#include "gipsi/geometry/normals.h"

#include <Eigen/Geometry>

namespace gipsi {
namespace {

/// (b − a) × (c − a) of triangle t: twice its area times its unit normal.
Vec3 DoubleAreaNormal(const Points& vertices, const Triangles& triangles, Index t) {
  const Vec3 a = vertices.col(triangles(0, t));
  return (vertices.col(triangles(1, t)) - a).cross(vertices.col(triangles(2, t)) - a);
}

}  // namespace

VecX TriangleAreas(const Points& vertices, const Triangles& triangles) {
  VecX areas(triangles.cols());
  for (Index t = 0; t < triangles.cols(); ++t)
    areas[t] = 0.5 * DoubleAreaNormal(vertices, triangles, t).norm();
  return areas;
}

Points FaceNormals(const Points& vertices, const Triangles& triangles) {
  Points normals(3, triangles.cols());
  for (Index t = 0; t < triangles.cols(); ++t) {
    const Vec3 n = DoubleAreaNormal(vertices, triangles, t);
    const double length = n.norm();
    normals.col(t) = length > 0 ? Vec3(n / length) : Vec3::Zero();
  }
  return normals;
}

void VertexNormals(const Points& vertices, const Triangles& triangles, Points& normals) {
  // n_v = Σ_{t ∋ v} A_t n_t / |Σ_{t ∋ v} A_t n_t|; the cross product is already 2 A_t n_t.
  normals.resize(3, vertices.cols());
  normals.setZero();
  for (Index t = 0; t < triangles.cols(); ++t) {
    const Vec3 n = DoubleAreaNormal(vertices, triangles, t);
    for (int a = 0; a < 3; ++a) normals.col(triangles(a, t)) += n;
  }
  for (Index v = 0; v < normals.cols(); ++v) {
    const double length = normals.col(v).norm();
    if (length > 0) normals.col(v) /= length;
  }
}

}  // namespace gipsi
