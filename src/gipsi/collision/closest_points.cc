#include "gipsi/collision/closest_points.h"

#include <algorithm>
#include <cmath>

namespace gipsi {

double ClosestParameterOnSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 <= 0) return 0;
  return std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
}

namespace {

PointTriangleResult OnEdge(const Vec3& p, const Vec3& a, const Vec3& b, int ia, int ib) {
  const double t = ClosestParameterOnSegment(p, a, b);
  PointTriangleResult r;
  r.point = a + t * (b - a);
  r.bary.setZero();
  r.bary[ia] = 1 - t;
  r.bary[ib] = t;
  r.distance = (p - r.point).norm();
  static constexpr TriangleFeature kEdge[3] = {TriangleFeature::kEdge01, TriangleFeature::kEdge12,
                                               TriangleFeature::kEdge20};
  static constexpr TriangleFeature kVertex[3] = {
      TriangleFeature::kVertex0, TriangleFeature::kVertex1, TriangleFeature::kVertex2};
  r.feature = t <= 0 ? kVertex[ia] : (t >= 1 ? kVertex[ib] : kEdge[ia]);
  return r;
}

PointTriangleResult AtVertex(const Vec3& p, const Vec3& v, int i) {
  static constexpr TriangleFeature kVertex[3] = {
      TriangleFeature::kVertex0, TriangleFeature::kVertex1, TriangleFeature::kVertex2};
  PointTriangleResult r;
  r.point = v;
  r.bary.setZero();
  r.bary[i] = 1;
  r.distance = (p - v).norm();
  r.feature = kVertex[i];
  return r;
}

}  // namespace

PointTriangleResult ClosestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b,
                                           const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  // Degenerate triangle: the closest point lies on one of its edges.
  if (ab.cross(ac).squaredNorm() <= 1e-30 * std::max(ab.squaredNorm(), ac.squaredNorm()) *
                                        std::max(ab.squaredNorm(), ac.squaredNorm())) {
    PointTriangleResult best = OnEdge(p, a, b, 0, 1);
    for (const auto& r : {OnEdge(p, b, c, 1, 2), OnEdge(p, c, a, 2, 0)})
      if (r.distance < best.distance) best = r;
    return best;
  }
  // Voronoi regions, Ericson §5.1.5.
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return AtVertex(p, a, 0);
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return AtVertex(p, b, 1);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return OnEdge(p, a, b, 0, 1);
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return AtVertex(p, c, 2);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return OnEdge(p, c, a, 2, 0);
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return OnEdge(p, b, c, 1, 2);
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  PointTriangleResult r;
  r.bary = Vec3(1 - v - w, v, w);
  r.point = a + v * ab + w * ac;
  r.distance = (p - r.point).norm();
  r.feature = TriangleFeature::kFace;
  return r;
}

SegmentSegmentResult ClosestPointsOfSegments(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                             const Vec3& q1) {
  // Ericson §5.1.9: minimise |p0 + s d1 − q0 − t d2|² over the unit square.
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  bool parallel = false;
  if (a <= 0 && e <= 0) {
    parallel = true;
  } else if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;  // >= 0, zero when parallel
      if (denom > 1e-14 * a * e) {
        s = std::clamp((b * f - c * e) / denom, 0.0, 1.0);
      } else {
        parallel = true;
        s = 0;
      }
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  SegmentSegmentResult res;
  res.s = s;
  res.t = t;
  res.on_p = p0 + s * d1;
  res.on_q = q0 + t * d2;
  res.distance = (res.on_p - res.on_q).norm();
  res.parallel = parallel;
  return res;
}

}  // namespace gipsi
