#include "gipsi/collision/proximity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "gipsi/collision/closest_points.h"

namespace gipsi {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Edge–edge contacts need closest points strictly inside both edges; within this fraction of
// an end, the pair is a vertex contact (reported by the vertex–triangle test).
constexpr double kInterior = 1e-9;

bool PointNearBox(const Vec3& p, const Box3& b, double gap) {
  return p[0] >= b.lo[0] - gap && p[0] <= b.hi[0] + gap && p[1] >= b.lo[1] - gap &&
         p[1] <= b.hi[1] + gap && p[2] >= b.lo[2] - gap && p[2] <= b.hi[2] + gap;
}

Box3 EdgeBox(const Vec3& p, const Vec3& q) {
  Box3 b;
  b.lo = p.cwiseMin(q);
  b.hi = p.cwiseMax(q);
  return b;
}

bool SharesVertex(const Triangles& tris, int t, int v) {
  return tris(0, t) == v || tris(1, t) == v || tris(2, t) == v;
}

// An edge pair that counts as an edge–edge contact (see proximity.h).
bool EdgeContact(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1, double thickness,
                 SegmentSegmentResult& r) {
  r = ClosestPointsOfSegments(a0, a1, b0, b1);
  return !r.parallel && r.distance < thickness && r.s > kInterior && r.s < 1 - kInterior &&
         r.t > kInterior && r.t < 1 - kInterior;
}

// True if every normal of cone a makes an angle below 90° with every normal of cone b: then no
// pair of features from them faces the other.
bool ConesAgree(const NormalCone& a, const NormalCone& b) {
  const double between = std::acos(std::clamp(a.axis.dot(b.axis), -1.0, 1.0));
  return between + a.half_angle + b.half_angle < 0.5 * std::numbers::pi;
}

}  // namespace

void ProximityQuery::Reset(std::vector<Best>& best, std::vector<int>& touched, Index n) {
  if (best.size() != static_cast<std::size_t>(n)) {
    best.assign(static_cast<std::size_t>(n), Best{kInf, -1, Vec3::Zero(), Vec3::Zero()});
    touched.clear();
  }
  for (int v : touched) best[static_cast<std::size_t>(v)].distance = kInf;
  touched.clear();
}

void ProximityQuery::Emit(const std::vector<Best>& best, std::vector<int>& touched,
                          std::vector<VertexTriangleContact>& out) {
  std::sort(touched.begin(), touched.end());
  for (int v : touched) {
    const Best& b = best[static_cast<std::size_t>(v)];
    out.push_back({v, b.triangle, b.bary, b.closest, b.distance});
  }
}

namespace {

// Offers triangle t of `s` as the closest to point p (vertex v); keeps the better one.
template <class BestT>
void OfferTriangle(const Vec3& p, int v, const CollisionSurface& s, int t, double thickness,
                   std::vector<BestT>& best, std::vector<int>& touched) {
  const Points& x = s.positions();
  const Triangles& tris = s.triangles();
  const PointTriangleResult r =
      ClosestPointOnTriangle(p, x.col(tris(0, t)), x.col(tris(1, t)), x.col(tris(2, t)));
  if (!(r.distance < thickness)) return;
  BestT& b = best[static_cast<std::size_t>(v)];
  if (b.distance == kInf) touched.push_back(v);
  if (r.distance < b.distance || (r.distance == b.distance && t < b.triangle)) {
    b.distance = r.distance;
    b.triangle = t;
    b.bary = r.bary;
    b.closest = r.point;
  }
}

}  // namespace

void ProximityQuery::Query(const CollisionSurface& a, const CollisionSurface& b, double thickness,
                           bool edge_edge, ProximityResult& out) {
  out.Clear();
  triangle_pairs_ = 0;
  node_pairs_ = 0;
  Reset(best_a_, touched_a_, a.num_vertices());
  Reset(best_b_, touched_b_, b.num_vertices());
  const AabbTree& ta = a.tree();
  const AabbTree& tb = b.tree();
  if (ta.empty() || tb.empty()) return;
  const double d = thickness;
  const Points& xa = a.positions();
  const Points& xb = b.positions();
  const Triangles& fa = a.triangles();
  const Triangles& fb = b.triangles();

  auto process = [&](int i, int j) {
    const Box3& box_i = ta.triangle_box(i);
    const Box3& box_j = tb.triangle_box(j);
    if (!box_i.Near(box_j, d)) return;
    ++triangle_pairs_;
    for (int k = 0; k < 3; ++k) {
      const int v = fa(k, i);
      if (a.vertex_owner()[static_cast<std::size_t>(v)] == i && PointNearBox(xa.col(v), box_j, d))
        OfferTriangle(xa.col(v), v, b, j, d, best_a_, touched_a_);
      const int w = fb(k, j);
      if (b.vertex_owner()[static_cast<std::size_t>(w)] == j && PointNearBox(xb.col(w), box_i, d))
        OfferTriangle(xb.col(w), w, a, i, d, best_b_, touched_b_);
    }
    if (!edge_edge) return;
    for (int ka = 0; ka < 3; ++ka) {
      const int ea = a.triangle_edges()(ka, i);
      if (a.edge_owner()[static_cast<std::size_t>(ea)] != i) continue;
      const Vec3 a0 = xa.col(a.edges()(0, ea)), a1 = xa.col(a.edges()(1, ea));
      const Box3 box_ea = EdgeBox(a0, a1);
      if (!box_ea.Near(box_j, d)) continue;
      for (int kb = 0; kb < 3; ++kb) {
        const int eb = b.triangle_edges()(kb, j);
        if (b.edge_owner()[static_cast<std::size_t>(eb)] != j) continue;
        const Vec3 b0 = xb.col(b.edges()(0, eb)), b1 = xb.col(b.edges()(1, eb));
        if (!box_ea.Near(EdgeBox(b0, b1), d)) continue;
        SegmentSegmentResult r;
        if (EdgeContact(a0, a1, b0, b1, d, r)) out.edges.push_back({ea, eb, r.s, r.t, r.distance});
      }
    }
  };

  const auto& na = ta.nodes();
  const auto& nb = tb.nodes();
  stack_.clear();
  stack_.emplace_back(0, 0);
  while (!stack_.empty()) {
    const auto [i, j] = stack_.back();
    stack_.pop_back();
    const AabbTree::Node& ni = na[static_cast<std::size_t>(i)];
    const AabbTree::Node& nj = nb[static_cast<std::size_t>(j)];
    ++node_pairs_;
    if (!ni.box.Near(nj.box, d)) continue;
    if (ni.is_leaf() && nj.is_leaf()) {
      for (int p = ni.first; p < ni.first + ni.count; ++p)
        for (int q = nj.first; q < nj.first + nj.count; ++q)
          process(ta.order()[static_cast<std::size_t>(p)], tb.order()[static_cast<std::size_t>(q)]);
    } else if (nj.is_leaf() || (!ni.is_leaf() && ni.box.SurfaceArea() >= nj.box.SurfaceArea())) {
      stack_.emplace_back(ni.first + 1, j);
      stack_.emplace_back(ni.first, j);
    } else {
      stack_.emplace_back(i, nj.first + 1);
      stack_.emplace_back(i, nj.first);
    }
  }
  Emit(best_a_, touched_a_, out.a_on_b);
  Emit(best_b_, touched_b_, out.b_on_a);
  std::sort(out.edges.begin(), out.edges.end(), [](const auto& p, const auto& q) {
    return p.edge_a < q.edge_a || (p.edge_a == q.edge_a && p.edge_b < q.edge_b);
  });
}

void ProximityQuery::QuerySelf(const CollisionSurface& s, double thickness, bool edge_edge,
                               ProximityResult& out) {
  out.Clear();
  triangle_pairs_ = 0;
  Reset(best_a_, touched_a_, s.num_vertices());
  const AabbTree& tree = s.tree();
  if (tree.empty()) return;
  const bool cones = tree.has_cones();
  const double d = thickness;
  const Points& x = s.positions();
  const Triangles& f = s.triangles();
  const Points& fn = s.face_normals();
  const Points& vn = s.vertex_normals();
  const Points& en = s.edge_normals();
  const auto& edges = s.edges();

  // One unordered pair of distinct triangles.
  auto process = [&](int i, int j) {
    const Box3& box_i = tree.triangle_box(i);
    const Box3& box_j = tree.triangle_box(j);
    if (!box_i.Near(box_j, d)) return;
    ++triangle_pairs_;
    for (int k = 0; k < 3; ++k) {
      const int v = f(k, i);
      if (s.vertex_owner()[static_cast<std::size_t>(v)] == i && !SharesVertex(f, j, v) &&
          vn.col(v).dot(fn.col(j)) < 0 && PointNearBox(x.col(v), box_j, d))
        OfferTriangle(x.col(v), v, s, j, d, best_a_, touched_a_);
      const int w = f(k, j);
      if (s.vertex_owner()[static_cast<std::size_t>(w)] == j && !SharesVertex(f, i, w) &&
          vn.col(w).dot(fn.col(i)) < 0 && PointNearBox(x.col(w), box_i, d))
        OfferTriangle(x.col(w), w, s, i, d, best_a_, touched_a_);
    }
    if (!edge_edge) return;
    for (int ka = 0; ka < 3; ++ka) {
      const int e1 = s.triangle_edges()(ka, i);
      if (s.edge_owner()[static_cast<std::size_t>(e1)] != i) continue;
      for (int kb = 0; kb < 3; ++kb) {
        const int e2 = s.triangle_edges()(kb, j);
        if (s.edge_owner()[static_cast<std::size_t>(e2)] != j) continue;
        const int ea = std::min(e1, e2), eb = std::max(e1, e2);
        if (edges(0, ea) == edges(0, eb) || edges(0, ea) == edges(1, eb) ||
            edges(1, ea) == edges(0, eb) || edges(1, ea) == edges(1, eb))
          continue;
        if (!(en.col(ea).dot(en.col(eb)) < 0)) continue;
        SegmentSegmentResult r;
        if (EdgeContact(x.col(edges(0, ea)), x.col(edges(1, ea)), x.col(edges(0, eb)),
                        x.col(edges(1, eb)), d, r))
          out.edges.push_back({ea, eb, r.s, r.t, r.distance});
      }
    }
  };

  const auto& nodes = tree.nodes();
  const auto& order = tree.order();
  stack_.clear();
  stack_.emplace_back(0, 0);
  while (!stack_.empty()) {
    const auto [i, j] = stack_.back();
    stack_.pop_back();
    const AabbTree::Node& ni = nodes[static_cast<std::size_t>(i)];
    const AabbTree::Node& nj = nodes[static_cast<std::size_t>(j)];
    if (i == j) {
      // Within one node: a node whose normals all lie within 45° of its axis cannot face itself.
      if (cones && 2 * tree.cone(i).half_angle < 0.5 * std::numbers::pi) continue;
      if (ni.is_leaf()) {
        for (int p = ni.first; p < ni.first + ni.count; ++p)
          for (int q = p + 1; q < ni.first + ni.count; ++q)
            process(order[static_cast<std::size_t>(p)], order[static_cast<std::size_t>(q)]);
      } else {
        stack_.emplace_back(ni.first, ni.first + 1);
        stack_.emplace_back(ni.first + 1, ni.first + 1);
        stack_.emplace_back(ni.first, ni.first);
      }
      continue;
    }
    if (!ni.box.Near(nj.box, d)) continue;
    if (cones && ConesAgree(tree.cone(i), tree.cone(j))) continue;
    if (ni.is_leaf() && nj.is_leaf()) {
      for (int p = ni.first; p < ni.first + ni.count; ++p)
        for (int q = nj.first; q < nj.first + nj.count; ++q)
          process(order[static_cast<std::size_t>(p)], order[static_cast<std::size_t>(q)]);
    } else if (nj.is_leaf() || (!ni.is_leaf() && ni.box.SurfaceArea() >= nj.box.SurfaceArea())) {
      stack_.emplace_back(ni.first + 1, j);
      stack_.emplace_back(ni.first, j);
    } else {
      stack_.emplace_back(i, nj.first + 1);
      stack_.emplace_back(i, nj.first);
    }
  }
  Emit(best_a_, touched_a_, out.a_on_b);
  std::sort(out.edges.begin(), out.edges.end(), [](const auto& p, const auto& q) {
    return p.edge_a < q.edge_a || (p.edge_a == q.edge_a && p.edge_b < q.edge_b);
  });
}

void ProximityQuery::QueryCapsule(const CollisionSurface& s, const Vec3& p0, const Vec3& p1,
                                  double radius, double thickness,
                                  std::vector<PrimitiveContact>& out) {
  out.clear();
  triangle_pairs_ = 0;
  const AabbTree& tree = s.tree();
  if (tree.empty()) return;
  Box3 tool;
  tool.Add(p0);
  tool.Add(p1);
  tool.lo.array() -= radius;
  tool.hi.array() += radius;
  const double d = thickness;
  const Points& x = s.positions();
  const Triangles& f = s.triangles();
  stack_.clear();
  stack_.emplace_back(0, 0);
  while (!stack_.empty()) {
    const int i = stack_.back().first;
    stack_.pop_back();
    const AabbTree::Node& n = tree.nodes()[static_cast<std::size_t>(i)];
    if (!n.box.Near(tool, d)) continue;
    if (!n.is_leaf()) {
      stack_.emplace_back(n.first + 1, 0);
      stack_.emplace_back(n.first, 0);
      continue;
    }
    for (int p = n.first; p < n.first + n.count; ++p) {
      const int t = tree.order()[static_cast<std::size_t>(p)];
      ++triangle_pairs_;
      for (int k = 0; k < 3; ++k) {
        const int v = f(k, t);
        if (s.vertex_owner()[static_cast<std::size_t>(v)] != t) continue;
        const Vec3 q = x.col(v);
        if (!PointNearBox(q, tool, d)) continue;
        const Vec3 c = p0 + ClosestParameterOnSegment(q, p0, p1) * (p1 - p0);
        const double dist = (q - c).norm();
        const double gap = dist - radius;
        if (!(gap < d)) continue;
        // At the axis itself the direction is undefined: push along the surface normal.
        const Vec3 normal = dist > 1e-12 * std::max(radius, 1e-300) ? Vec3((q - c) / dist)
                                                                    : Vec3(s.face_normals().col(t));
        out.push_back({v, normal, c + radius * normal, gap});
      }
    }
  }
  std::sort(out.begin(), out.end(),
            [](const auto& a, const auto& b) { return a.vertex < b.vertex; });
}

void BruteForceProximity(const CollisionSurface& a, const CollisionSurface& b, double thickness,
                         bool edge_edge, bool self, ProximityResult& out) {
  out.Clear();
  auto closest = [&](const CollisionSurface& from, const CollisionSurface& to,
                     std::vector<VertexTriangleContact>& list) {
    for (Index v = 0; v < from.num_vertices(); ++v) {
      if (from.vertex_owner()[static_cast<std::size_t>(v)] < 0) continue;
      VertexTriangleContact best;
      best.distance = kInf;
      const Vec3 p = from.positions().col(v);
      for (Index t = 0; t < to.num_triangles(); ++t) {
        if (self && (SharesVertex(to.triangles(), int(t), int(v)) ||
                     !(from.vertex_normals().col(v).dot(to.face_normals().col(t)) < 0)))
          continue;
        const auto& x = to.positions();
        const auto& f = to.triangles();
        const PointTriangleResult r =
            ClosestPointOnTriangle(p, x.col(f(0, t)), x.col(f(1, t)), x.col(f(2, t)));
        if (r.distance < best.distance) best = {int(v), int(t), r.bary, r.point, r.distance};
      }
      if (best.distance < thickness) list.push_back(best);
    }
  };
  closest(a, b, out.a_on_b);
  if (!self) closest(b, a, out.b_on_a);
  if (!edge_edge) return;
  for (Index ea = 0; ea < a.num_edges(); ++ea) {
    for (Index eb = self ? ea + 1 : 0; eb < b.num_edges(); ++eb) {
      const auto& E = a.edges();
      const auto& F = b.edges();
      if (self) {
        if (E(0, ea) == F(0, eb) || E(0, ea) == F(1, eb) || E(1, ea) == F(0, eb) ||
            E(1, ea) == F(1, eb))
          continue;
        if (!(a.edge_normals().col(ea).dot(b.edge_normals().col(eb)) < 0)) continue;
      }
      SegmentSegmentResult r;
      if (EdgeContact(a.positions().col(E(0, ea)), a.positions().col(E(1, ea)),
                      b.positions().col(F(0, eb)), b.positions().col(F(1, eb)), thickness, r))
        out.edges.push_back({int(ea), int(eb), r.s, r.t, r.distance});
    }
  }
}

}  // namespace gipsi
