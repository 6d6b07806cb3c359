#pragma once
/// @file
/// Narrow-phase proximity queries between collision surfaces: every vertex–triangle and
/// edge–edge pair of features closer than a contact thickness, found by traversing two AABB
/// trees (or one tree against itself) and computing exact closest points at the leaves.
///
/// Contact sets (what a query reports, and what the tests check against brute force):
///  - vertex–triangle: for each vertex of one surface, the closest point of the other surface
///    when it is closer than the thickness (one contact per vertex and surface pair; ties keep
///    the lowest triangle id);
///  - edge–edge: every pair of edges whose closest points are closer than the thickness and
///    interior to both edges (end points are vertex contacts already); parallel edges are left
///    to the vertex contacts of their end points.
///  - self-collision: as above within one surface, skipping features that share a vertex
///    (adjacency) and pairs whose normals do not face each other (n_a · n_b >= 0, with vertex
///    and edge normals averaged from the incident faces), so a flat or gently curved surface
///    never touches itself; normal cones cull whole subtrees that cannot face each other.
/// Output is sorted (by vertex, then by edge pair), hence deterministic.

#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/collision/collision_surface.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A vertex of one surface near a triangle of another (or the same) surface. Plain struct.
struct VertexTriangleContact {
  int vertex = -1;    ///< vertex of the first surface
  int triangle = -1;  ///< triangle of the second surface
  Vec3 bary;          ///< barycentric weights of the closest point on the triangle
  Vec3 closest;       ///< the closest point
  double distance = 0;
};

/// Two edges near each other. Plain struct.
struct EdgeEdgeContact {
  int edge_a = -1, edge_b = -1;  ///< edges of the first and second surface
  double s = 0, t = 0;           ///< parameters of the closest points along each edge
  double distance = 0;
};

/// Everything a query finds. Plain struct; clear-and-reuse keeps its capacity.
struct ProximityResult {
  std::vector<VertexTriangleContact> a_on_b;  ///< vertices of A near triangles of B
  std::vector<VertexTriangleContact>
      b_on_a;  ///< vertices of B near triangles of A (empty for self)
  std::vector<EdgeEdgeContact> edges;
  void Clear() {
    a_on_b.clear();
    b_on_a.clear();
    edges.clear();
  }
  [[nodiscard]] std::size_t size() const { return a_on_b.size() + b_on_a.size() + edges.size(); }
};

/// A vertex near a convex tool primitive (sphere or capsule). Plain struct.
struct PrimitiveContact {
  int vertex = -1;
  Vec3 normal;     ///< unit, from the primitive's surface toward the vertex
  Vec3 on_tool;    ///< closest point on the primitive's surface
  double gap = 0;  ///< signed distance of the vertex from the primitive (negative inside)
};

/// Runs queries with preallocated scratch space. Not copyable; movable. Not thread-safe.
class ProximityQuery {
 public:
  ProximityQuery() = default;
  ProximityQuery(ProximityQuery&&) = default;
  ProximityQuery& operator=(ProximityQuery&&) = default;
  ProximityQuery(const ProximityQuery&) = delete;
  ProximityQuery& operator=(const ProximityQuery&) = delete;

  /// Contacts between surfaces `a` and `b` (both Update()d) closer than `thickness` (> 0).
  void Query(const CollisionSurface& a, const CollisionSurface& b, double thickness, bool edge_edge,
             ProximityResult& out);
  /// Self-contacts of `s` (Update()d with cones) closer than `thickness`.
  void QuerySelf(const CollisionSurface& s, double thickness, bool edge_edge, ProximityResult& out);
  /// Vertices of `s` closer than `thickness` to the capsule of radius `radius` around segment
  /// [p0, p1] (a sphere when p0 == p1).
  void QueryCapsule(const CollisionSurface& s, const Vec3& p0, const Vec3& p1, double radius,
                    double thickness, std::vector<PrimitiveContact>& out);

  /// Triangle pairs whose boxes were near in the last query (a cost measure).
  [[nodiscard]] std::int64_t last_triangle_pairs() const { return triangle_pairs_; }
  /// Node pairs whose boxes were tested in the last two-surface query (a cost measure).
  [[nodiscard]] std::int64_t last_node_pairs() const { return node_pairs_; }

 private:
  struct Best {
    double distance;
    int triangle;
    Vec3 bary, closest;
  };
  void Reset(std::vector<Best>& best, std::vector<int>& touched, Index n);
  static void Emit(const std::vector<Best>& best, std::vector<int>& touched,
                   std::vector<VertexTriangleContact>& out);

  std::vector<Best> best_a_, best_b_;
  std::vector<int> touched_a_, touched_b_;
  std::vector<std::pair<int, int>> stack_;
  std::int64_t triangle_pairs_ = 0;
  std::int64_t node_pairs_ = 0;
};

/// Brute-force reference of `ProximityQuery::Query` / `QuerySelf` (every feature pair; for
/// tests). `self` selects the self-collision rules; then `b` must be `a`.
void BruteForceProximity(const CollisionSurface& a, const CollisionSurface& b, double thickness,
                         bool edge_edge, bool self, ProximityResult& out);

}  // namespace gipsi
GIPSI_EXPORT_END
