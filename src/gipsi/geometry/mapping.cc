#include "gipsi/geometry/mapping.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include "gipsi/base/error.h"
#include "gipsi/geometry/spatial_grid.h"

namespace gipsi {
namespace {

/// A target counts as inside a tet when its smallest barycentric coordinate is >= −kInsideTol
/// (coordinates are dimensionless; this only absorbs round-off on shared faces).
constexpr double kInsideTol = 1e-12;

/// Barycentric coordinates (u, v, w) of the point of triangle (a, b, c) closest to p, after
/// Ericson, "Real-Time Collision Detection" (2005), §5.1.5: the Voronoi regions of the
/// vertices, then of the edges, then the face. Degenerate triangles fall back to their edges.
Vec3 ClosestOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0 && d1 - d3 > 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0 && d2 - d6 > 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0 && (d4 - d3) + (d5 - d6) > 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double sum = va + vb + vc;
  if (sum > 0) {
    const double v = vb / sum, w = vc / sum;
    return {1 - v - w, v, w};
  }
  // Degenerate (zero-area) triangle: the closest of the closest points on its three edges.
  auto on_segment = [&](const Vec3& s0, const Vec3& s1) {
    const Vec3 d = s1 - s0;
    const double len2 = d.squaredNorm();
    return len2 > 0 ? std::clamp((p - s0).dot(d) / len2, 0.0, 1.0) : 0.0;
  };
  const std::array<Vec3, 3> candidates = {Vec3(1 - on_segment(a, b), on_segment(a, b), 0),
                                          Vec3(0, 1 - on_segment(b, c), on_segment(b, c)),
                                          Vec3(1 - on_segment(a, c), 0, on_segment(a, c))};
  Vec3 best = candidates[0];
  double best_d2 = std::numeric_limits<double>::infinity();
  for (const Vec3& l : candidates) {
    const double d2c = (l[0] * a + l[1] * b + l[2] * c - p).squaredNorm();
    if (d2c < best_d2) {
      best_d2 = d2c;
      best = l;
    }
  }
  return best;
}

/// Corner positions of tet e.
std::array<Vec3, 4> TetCorners(const Points& nodes, const Tets& tets, Index e) {
  return {nodes.col(tets(0, e)), nodes.col(tets(1, e)), nodes.col(tets(2, e)),
          nodes.col(tets(3, e))};
}

/// Barycentric coordinates of p in tet x: p = Σ λ_k x_k, Σ λ_k = 1. Returns false for a
/// degenerate tet.
bool TetBarycentric(const std::array<Vec3, 4>& x, const Vec3& p, Eigen::Vector4d& lambda) {
  Mat3 J;
  J << x[1] - x[0], x[2] - x[0], x[3] - x[0];
  const double det = J.determinant();
  double longest2 = 0;
  for (int k = 1; k < 4; ++k) longest2 = std::max(longest2, (x[k] - x[0]).squaredNorm());
  if (!(std::abs(det) > 1e-14 * longest2 * std::sqrt(longest2))) return false;
  const Vec3 mu = J.inverse() * (p - x[0]);
  lambda << 1 - mu.sum(), mu;
  return true;
}

/// Closest point of tet x to p as barycentric weights; returns the distance (0 inside).
double ClosestOnTet(const std::array<Vec3, 4>& x, const Vec3& p, Eigen::Vector4d& weights) {
  if (TetBarycentric(x, p, weights) && weights.minCoeff() >= 0) return 0;
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  double best = std::numeric_limits<double>::infinity();
  for (const auto& f : kFaces) {
    const Vec3 l = ClosestOnTriangle(p, x[f[0]], x[f[1]], x[f[2]]);
    const double d = (l[0] * x[f[0]] + l[1] * x[f[1]] + l[2] * x[f[2]] - p).norm();
    if (d < best) {
      best = d;
      weights.setZero();
      for (int a = 0; a < 3; ++a) weights[f[a]] = l[a];
    }
  }
  return best;
}

/// Throws InputError naming `what` unless every target is finite.
void CheckTargets(const Points& targets, std::string_view what) {
  if (targets.allFinite()) return;
  for (Index j = 0; j < targets.cols(); ++j)
    if (!targets.col(j).allFinite())
      ThrowInputError("", what, fmt::format("target {} has non-finite coordinates", j));
}

/// Bounding boxes of the elements of `conn` (R by E) over `nodes`.
template <class Conn>
SpatialGrid GridOfElements(const Points& nodes, const Conn& conn) {
  Points lo(3, conn.cols()), hi(3, conn.cols());
  for (Index e = 0; e < conn.cols(); ++e) {
    lo.col(e) = hi.col(e) = nodes.col(conn(0, e));
    for (Index a = 1; a < conn.rows(); ++a) {
      lo.col(e) = lo.col(e).cwiseMin(nodes.col(conn(a, e)));
      hi.col(e) = hi.col(e).cwiseMax(nodes.col(conn(a, e)));
    }
  }
  return SpatialGrid(lo, hi);
}

}  // namespace

PointMap PointMap::BarycentricInTets(const Points& nodes, const Tets& tets, const Points& targets) {
  PointMap map;
  map.indices_.setZero(4, targets.cols());
  map.weights_.setZero(4, targets.cols());
  if (targets.cols() == 0) return map;
  if (tets.cols() == 0)
    ThrowInputError(
        "", "barycentric embedding",
        fmt::format("cannot embed {} points in a mesh without tetrahedra", targets.cols()));
  CheckTargets(targets, "barycentric embedding");
  const SpatialGrid grid = GridOfElements(nodes, tets);
  Eigen::Vector4d lambda, best_lambda, weights;
  for (Index j = 0; j < targets.cols(); ++j) {
    const Vec3 p = targets.col(j);
    // The tet of the cell that contains p most deeply (largest smallest coordinate).
    int best = -1;
    double best_min = -std::numeric_limits<double>::infinity();
    grid.ForEachInCell(p, [&](int e) {
      if (!TetBarycentric(TetCorners(nodes, tets, e), p, lambda)) return;
      const double m = lambda.minCoeff();
      if (m > best_min) {
        best_min = m;
        best = e;
        best_lambda = lambda;
      }
    });
    if (best < 0 || best_min < -kInsideTol) {  // outside every tet: nearest, clamped
      double distance = 0;
      best = grid.FindNearest(
          p, [&](int e) { return ClosestOnTet(TetCorners(nodes, tets, e), p, weights); }, distance);
      ClosestOnTet(TetCorners(nodes, tets, best), p, best_lambda);
    }
    Vec3 reproduced = Vec3::Zero();
    for (int k = 0; k < 4; ++k) {
      map.indices_(k, j) = tets(k, best);
      map.weights_(k, j) = best_lambda[k];
      reproduced += best_lambda[k] * nodes.col(tets(k, best));
    }
    map.max_distance_ = std::max(map.max_distance_, (reproduced - p).norm());
  }
  return map;
}

PointMap PointMap::BarycentricOnTriangles(const Points& vertices, const Triangles& triangles,
                                          const Points& targets) {
  PointMap map;
  map.indices_.setZero(4, targets.cols());
  map.weights_.setZero(4, targets.cols());
  if (targets.cols() == 0) return map;
  if (triangles.cols() == 0)
    ThrowInputError(
        "", "surface embedding",
        fmt::format("cannot project {} points onto a surface without triangles", targets.cols()));
  CheckTargets(targets, "surface embedding");
  const SpatialGrid grid = GridOfElements(vertices, triangles);
  auto closest = [&](Index t, const Vec3& p) {
    return ClosestOnTriangle(p, vertices.col(triangles(0, t)), vertices.col(triangles(1, t)),
                             vertices.col(triangles(2, t)));
  };
  for (Index j = 0; j < targets.cols(); ++j) {
    const Vec3 p = targets.col(j);
    double distance = 0;
    const int best = grid.FindNearest(
        p,
        [&](int t) {
          const Vec3 l = closest(t, p);
          return (l[0] * vertices.col(triangles(0, t)) + l[1] * vertices.col(triangles(1, t)) +
                  l[2] * vertices.col(triangles(2, t)) - p)
              .norm();
        },
        distance);
    const Vec3 l = closest(best, p);
    Vec3 reproduced = Vec3::Zero();
    for (int k = 0; k < 3; ++k) {
      map.indices_(k, j) = triangles(k, best);
      map.weights_(k, j) = l[k];
      reproduced += l[k] * vertices.col(triangles(k, best));
    }
    map.max_distance_ = std::max(map.max_distance_, (reproduced - p).norm());
  }
  return map;
}

PointMap PointMap::Nearest(const Points& sources, const Points& targets) {
  PointMap map;
  map.indices_.setZero(4, targets.cols());
  map.weights_.setZero(4, targets.cols());
  if (targets.cols() == 0) return map;
  if (sources.cols() == 0)
    ThrowInputError("", "nearest-point map",
                    fmt::format("cannot map {} points to an empty set of sources", targets.cols()));
  CheckTargets(targets, "nearest-point map");
  const SpatialGrid grid(sources, sources);
  for (Index j = 0; j < targets.cols(); ++j) {
    const Vec3 p = targets.col(j);
    double distance = 0;
    const int best = grid.FindNearest(
        p, [&](int s) { return (sources.col(s) - p).norm(); }, distance);
    map.indices_(0, j) = best;
    map.weights_(0, j) = 1;
    map.max_distance_ = std::max(map.max_distance_, distance);
  }
  return map;
}

void PointMap::Apply(const Eigen::Ref<const Eigen::MatrixXd>& source,
                     Eigen::Ref<Eigen::MatrixXd> out) const {
  GIPSI_CHECK(out.rows() == source.rows() && out.cols() == num_targets(),
              "PointMap::Apply: out is {} by {}, expected {} by {} (source rows by targets)",
              out.rows(), out.cols(), source.rows(), num_targets());
  if (num_targets() == 0) return;
  GIPSI_CHECK(indices_.maxCoeff() < source.cols(),
              "PointMap::Apply: source has {} columns, the map refers to column {}", source.cols(),
              indices_.maxCoeff());
  for (Index j = 0; j < num_targets(); ++j) {
    const auto idx = indices_.col(j);
    const auto w = weights_.col(j);
    out.col(j) = w[0] * source.col(idx[0]) + w[1] * source.col(idx[1]) + w[2] * source.col(idx[2]) +
                 w[3] * source.col(idx[3]);
  }
}

void PointMap::ApplyMarked(const Eigen::Ref<const Eigen::MatrixXd>& source,
                           Eigen::Ref<Eigen::MatrixXd> out, double marker) const {
  Apply(source, out);
  for (Index j = 0; j < num_targets(); ++j)
    for (int k = 0; k < 4; ++k) {
      if (weights_(k, j) == 0) continue;
      const Index item = indices_(k, j);
      for (Index c = 0; c < source.rows(); ++c)
        if (source(c, item) == marker) out(c, j) = marker;
    }
}

PointMap PointMap::FromWeights(Eigen::Matrix4Xi indices, Eigen::Matrix4Xd weights,
                               double max_distance) {
  GIPSI_CHECK(indices.cols() == weights.cols());
  PointMap map;
  map.indices_ = std::move(indices);
  map.weights_ = std::move(weights);
  map.max_distance_ = max_distance;
  return map;
}

}  // namespace gipsi
