#pragma once
/// @file
/// Exact closest points between a point and a triangle, and between two segments: the leaf
/// tests of the narrow phase. Allocation-free and branch-complete (degenerate triangles and
/// segments are handled). Algorithms after Ericson, "Real-Time Collision Detection" (2005),
/// §5.1.5 (Voronoi regions of a triangle) and §5.1.9 (segment–segment).

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Which feature of a triangle holds the closest point.
enum class TriangleFeature : std::uint8_t {
  kFace,     ///< the interior
  kEdge01,   ///< edge from vertex 0 to vertex 1 (open segment)
  kEdge12,   ///< edge from vertex 1 to vertex 2
  kEdge20,   ///< edge from vertex 2 to vertex 0
  kVertex0,  ///< a vertex
  kVertex1,
  kVertex2,
};

/// Closest point on triangle (a, b, c) to a point. Plain struct.
struct PointTriangleResult {
  Vec3 point;       ///< the closest point, = bary[0] a + bary[1] b + bary[2] c
  Vec3 bary;        ///< barycentric weights, each in [0, 1], summing to 1
  double distance;  ///< |p − point| [same units as the input]
  TriangleFeature feature;
};

/// The closest point of triangle (a, b, c) to `p`. A degenerate (zero-area) triangle is treated
/// as its longest edge.
PointTriangleResult ClosestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b,
                                           const Vec3& c);

/// Closest points of segments p(s) = p0 + s (p1 − p0) and q(t) = q0 + t (q1 − q0), s, t in
/// [0, 1]. Plain struct.
struct SegmentSegmentResult {
  double s, t;      ///< parameters of the closest points
  Vec3 on_p, on_q;  ///< the closest points
  double distance;  ///< |on_p − on_q|
  /// True when the segments are parallel (then the closest pair is not unique; the one
  /// returned has s or t at an end).
  bool parallel;
};

/// Closest points between two segments (degenerate segments are points).
SegmentSegmentResult ClosestPointsOfSegments(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                             const Vec3& q1);

/// Closest point on segment [a, b] to p; returns the parameter t in [0, 1].
double ClosestParameterOnSegment(const Vec3& p, const Vec3& a, const Vec3& b);

}  // namespace gipsi
GIPSI_EXPORT_END
