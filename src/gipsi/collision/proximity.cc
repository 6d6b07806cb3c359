#include "gipsi/collision/proximity.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
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

inline Box3 EdgeBox(const Vec3& p, const Vec3& q) {
  Box3 b;
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = std::min(p[k], q[k]);
    b.hi[k] = std::max(p[k], q[k]);
  }
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

// A cheap, conservative rejection in front of EdgeContact: true when the infinite lines
// through the segments are provably farther apart than `thickness` (then so are the segments,
// and EdgeContact would reject the pair). The line distance is |n · r| / |n| with
// n = (a1 − a0) × (b1 − b0) and r = a0 − b0; both sides are squared (no square root), and the
// bound is widened by margins 10⁶ times the rounding errors of the computation here and of
// the exact closest points, so it never rejects a pair that EdgeContact would accept.
// Near-parallel edges (|n| small) are never rejected.
bool LinesApart(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1, double thickness) {
  const double d1[3] = {a1[0] - a0[0], a1[1] - a0[1], a1[2] - a0[2]};
  const double d2[3] = {b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2]};
  const double r[3] = {a0[0] - b0[0], a0[1] - b0[1], a0[2] - b0[2]};
  const double n[3] = {d1[1] * d2[2] - d1[2] * d2[1], d1[2] * d2[0] - d1[0] * d2[2],
                       d1[0] * d2[1] - d1[1] * d2[0]};
  const double nr = std::abs(n[0] * r[0] + n[1] * r[1] + n[2] * r[2]);
  const double n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  auto l1 = [](const double* v) { return std::abs(v[0]) + std::abs(v[1]) + std::abs(v[2]); };
  // |error of n · r| <= ~10 eps |d1| |d2| |r|; the exact closest points err by ~eps times the
  // coordinates' size. Margins: 1e-10 (about 10⁶ eps) times those scales.
  const double scale = l1(d1) * l1(d2);
  const double lower = nr - 1e-10 * scale * l1(r);
  const double reach =
      thickness + 1e-10 * (thickness + l1(a0.data()) + l1(b0.data()) + l1(d1) + l1(d2));
  return lower > 0 && lower * lower > reach * reach * (n2 + 1e-10 * scale * scale);
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

// Offers the triangle t with corners c as the closest to point p (vertex v); keeps the better
// one (ties: the lower triangle id, so the order of the offers does not matter).
template <class BestT>
void OfferCorners(const Vec3& p, int v, const Vec3 (&c)[3], int t, double thickness,
                  std::vector<BestT>& best, std::vector<int>& touched) {
  const PointTriangleResult r = ClosestPointOnTriangle(p, c[0], c[1], c[2]);
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

// Triangle t of a surface with its corners loaded: vertex ids, positions, owned features.
struct LoadedTriangle {
  int id;
  unsigned owned;  // CollisionSurface::owned_features bits
  int vertex[3];
  Vec3 corner[3];
  LoadedTriangle(const CollisionSurface& s, int t)
      : id(t), owned(s.owned_features()[static_cast<std::size_t>(t)]) {
    for (int k = 0; k < 3; ++k) {
      vertex[k] = s.triangles()(k, t);
      corner[k] = s.positions().col(vertex[k]);
    }
  }
  // Which owned features of this triangle can be within `gap` of `box` (so of anything
  // inside it): bit k of `vertices` for vertex k (inside the box grown by gap), bit k of
  // `edges` for edge k, from corner k to corner k + 1 (its box meets the grown box, i.e. its
  // end points are not both beyond the same face). One classification of the three corners
  // serves both: no branches, and no edge boxes for the edges that cannot be near.
  void NearFeatures(const Box3& box, double gap, unsigned& vertices, unsigned& edges) const {
    const double lo[3] = {box.lo[0] - gap, box.lo[1] - gap, box.lo[2] - gap};
    const double hi[3] = {box.hi[0] + gap, box.hi[1] + gap, box.hi[2] + gap};
    unsigned beyond[3];  // bit 2a: below face a; bit 2a + 1: above it
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = corner[k];
      beyond[k] =
          static_cast<unsigned>(p[0] < lo[0]) | static_cast<unsigned>(p[0] > hi[0]) << 1 |
          static_cast<unsigned>(p[1] < lo[1]) << 2 | static_cast<unsigned>(p[1] > hi[1]) << 3 |
          static_cast<unsigned>(p[2] < lo[2]) << 4 | static_cast<unsigned>(p[2] > hi[2]) << 5;
    }
    vertices = static_cast<unsigned>(beyond[0] == 0) | static_cast<unsigned>(beyond[1] == 0) << 1 |
               static_cast<unsigned>(beyond[2] == 0) << 2;
    edges = static_cast<unsigned>((beyond[0] & beyond[1]) == 0) |
            static_cast<unsigned>((beyond[1] & beyond[2]) == 0) << 1 |
            static_cast<unsigned>((beyond[2] & beyond[0]) == 0) << 2;
    vertices &= owned & 7u;
    edges &= owned >> 3;
  }
  [[nodiscard]] Box3 EdgeBoxOf(int k) const {
    return EdgeBox(corner[k], corner[k == 2 ? 0 : k + 1]);
  }
  // Edge k's end points in the orientation of CollisionSurface::edges (smaller vertex first).
  [[nodiscard]] const Vec3& EdgeStart(int k) const {
    const int k1 = k == 2 ? 0 : k + 1;
    return vertex[k] < vertex[k1] ? corner[k] : corner[k1];
  }
  [[nodiscard]] const Vec3& EdgeEnd(int k) const {
    const int k1 = k == 2 ? 0 : k + 1;
    return vertex[k] < vertex[k1] ? corner[k1] : corner[k];
  }
};

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
  const Box3* box_a = ta.ordered_boxes().data();
  const Box3* box_b = tb.ordered_boxes().data();
  const int* order_a = ta.order().data();
  const int* order_b = tb.order().data();

  // Triangles at leaf positions p of a and q of b, whose boxes are near. Every test below is
  // a conservative filter in front of the exact closest-point computation, so the contact set
  // is exactly that of the brute force; the masks keep the branches few (see Box3::Near).
  auto process = [&](int p, int q) {
    const Box3& box_i = box_a[p];
    const Box3& box_j = box_b[q];
    ++triangle_pairs_;
    const LoadedTriangle ti(a, order_a[p]), tj(b, order_b[q]);
    // A vertex can only be within d of a triangle if it is within d of the triangle's box; an
    // edge pair only if each edge's box is near the other's triangle box and the edge boxes
    // are near each other.
    unsigned vi, ei, vj, ej;
    ti.NearFeatures(box_j, d, vi, ei);
    tj.NearFeatures(box_i, d, vj, ej);
    for (unsigned m = vi | (vj << 3); m != 0; m &= m - 1) {
      const int bit = std::countr_zero(m);
      if (bit < 3)
        OfferCorners(ti.corner[bit], ti.vertex[bit], tj.corner, tj.id, d, best_a_, touched_a_);
      else
        OfferCorners(tj.corner[bit - 3], tj.vertex[bit - 3], ti.corner, ti.id, d, best_b_,
                     touched_b_);
    }
    if (!edge_edge || ei == 0 || ej == 0) return;
    for (; ei != 0; ei &= ei - 1) {
      const int ka = std::countr_zero(ei);
      const Box3 edge_i = ti.EdgeBoxOf(ka);
      for (unsigned m = ej; m != 0; m &= m - 1) {
        const int kb = std::countr_zero(m);
        if (!edge_i.Near(tj.EdgeBoxOf(kb), d)) continue;
        const Vec3 &a0 = ti.EdgeStart(ka), &a1 = ti.EdgeEnd(ka);
        const Vec3 &b0 = tj.EdgeStart(kb), &b1 = tj.EdgeEnd(kb);
        if (LinesApart(a0, a1, b0, b1, d)) continue;
        SegmentSegmentResult r;
        if (EdgeContact(a0, a1, b0, b1, d, r))
          out.edges.push_back(
              {a.triangle_edges()(ka, ti.id), b.triangle_edges()(kb, tj.id), r.s, r.t, r.distance});
      }
    }
  };

  const AabbTree::Node* na = ta.nodes().data();
  const AabbTree::Node* nb = tb.nodes().data();
  node_pairs_ = 1;
  if (!na[0].box.Near(nb[0].box, d)) return;
  // The stack holds node pairs whose boxes are near; children are tested before they are
  // pushed, and pushed without a branch (written always, kept if near).
  if (stack_.size() < 64) stack_.resize(64);
  std::size_t top = 0;
  stack_[top++] = {0, 0};
  while (top > 0) {
    const auto [i, j] = stack_[--top];
    const AabbTree::Node& ni = na[i];
    const AabbTree::Node& nj = nb[j];
    if (ni.is_leaf() && nj.is_leaf()) {
      // All triangle pairs of the two leaves (at most 8 × 8) as one bit mask.
      std::uint64_t mask = 0;
      for (int p = 0; p < ni.count; ++p)
        for (int q = 0; q < nj.count; ++q)
          mask |= static_cast<std::uint64_t>(box_a[ni.first + p].Near(box_b[nj.first + q], d))
                  << (8 * p + q);
      for (; mask != 0; mask &= mask - 1) {
        const int bit = std::countr_zero(mask);
        process(ni.first + bit / 8, nj.first + bit % 8);
      }
      continue;
    }
    if (top + 2 > stack_.size()) stack_.resize(2 * stack_.size());
    node_pairs_ += 2;
    // Descend the larger node (by surface area) unless it is a leaf.
    if (nj.is_leaf() || (!ni.is_leaf() && ni.area >= nj.area)) {
      const int c = ni.first;
      stack_[top] = {c + 1, j};
      top += static_cast<std::size_t>(na[c + 1].box.Near(nj.box, d));
      stack_[top] = {c, j};
      top += static_cast<std::size_t>(na[c].box.Near(nj.box, d));
    } else {
      const int c = nj.first;
      stack_[top] = {i, c + 1};
      top += static_cast<std::size_t>(ni.box.Near(nb[c + 1].box, d));
      stack_[top] = {i, c};
      top += static_cast<std::size_t>(ni.box.Near(nb[c].box, d));
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
  const auto& order = tree.order();

  // One unordered pair of distinct triangles, at leaf positions p and q.
  auto process = [&](int p, int q) {
    const int i = order[static_cast<std::size_t>(p)], j = order[static_cast<std::size_t>(q)];
    const Box3& box_i = tree.ordered_box(p);
    const Box3& box_j = tree.ordered_box(q);
    if (!box_i.Near(box_j, d)) return;
    ++triangle_pairs_;
    // The box filters of Query first (see there), then the self-collision rules.
    const LoadedTriangle ti(s, i), tj(s, j);
    unsigned vi, ei, vj, ej;
    ti.NearFeatures(box_j, d, vi, ei);
    tj.NearFeatures(box_i, d, vj, ej);
    for (unsigned m = vi | (vj << 3); m != 0; m &= m - 1) {
      const int bit = std::countr_zero(m);
      const LoadedTriangle& from = bit < 3 ? ti : tj;
      const LoadedTriangle& to = bit < 3 ? tj : ti;
      const int v = from.vertex[bit % 3];
      if (!SharesVertex(f, to.id, v) && vn.col(v).dot(fn.col(to.id)) < 0)
        OfferCorners(from.corner[bit % 3], v, to.corner, to.id, d, best_a_, touched_a_);
    }
    if (!edge_edge || ei == 0 || ej == 0) return;
    for (; ei != 0; ei &= ei - 1) {
      const int ka = std::countr_zero(ei);
      const int e1 = s.triangle_edges()(ka, i);
      const Box3 edge_i = ti.EdgeBoxOf(ka);
      for (unsigned m = ej; m != 0; m &= m - 1) {
        const int kb = std::countr_zero(m);
        if (!edge_i.Near(tj.EdgeBoxOf(kb), d)) continue;
        const int e2 = s.triangle_edges()(kb, j);
        const int ea = std::min(e1, e2), eb = std::max(e1, e2);
        if (edges(0, ea) == edges(0, eb) || edges(0, ea) == edges(1, eb) ||
            edges(1, ea) == edges(0, eb) || edges(1, ea) == edges(1, eb))
          continue;
        if (!(en.col(ea).dot(en.col(eb)) < 0)) continue;
        const Vec3 a0 = x.col(edges(0, ea)), a1 = x.col(edges(1, ea));
        const Vec3 b0 = x.col(edges(0, eb)), b1 = x.col(edges(1, eb));
        if (LinesApart(a0, a1, b0, b1, d)) continue;
        SegmentSegmentResult r;
        if (EdgeContact(a0, a1, b0, b1, d, r)) out.edges.push_back({ea, eb, r.s, r.t, r.distance});
      }
    }
  };

  const auto& nodes = tree.nodes();
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
          for (int q = p + 1; q < ni.first + ni.count; ++q) process(p, q);
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
        for (int q = nj.first; q < nj.first + nj.count; ++q) process(p, q);
    } else if (nj.is_leaf() || (!ni.is_leaf() && ni.area >= nj.area)) {
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
