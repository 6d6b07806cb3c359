#include "gipsi/collision/aabb_tree.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "gipsi/base/error.h"

namespace gipsi {

NormalCone MergeCones(const NormalCone& a, const NormalCone& b) {
  if (a.half_angle >= std::numbers::pi || b.half_angle >= std::numbers::pi)
    return {a.axis, std::numbers::pi};
  const double between = std::acos(std::clamp(a.axis.dot(b.axis), -1.0, 1.0));
  // Already nested?
  if (between + b.half_angle <= a.half_angle) return a;
  if (between + a.half_angle <= b.half_angle) return b;
  const double half = 0.5 * (between + a.half_angle + b.half_angle);
  if (half >= std::numbers::pi) return {a.axis, std::numbers::pi};
  // Rotate a.axis toward b.axis by (half − a.half_angle) in their common plane.
  const Vec3 perp = b.axis - a.axis.dot(b.axis) * a.axis;
  const double perp_norm = perp.norm();
  if (perp_norm < 1e-12) return {a.axis, half};
  const double turn = half - a.half_angle;
  const Vec3 axis = std::cos(turn) * a.axis + std::sin(turn) * (perp / perp_norm);
  // Slack for round-off so that the cone contains both inputs.
  return {axis.normalized(), std::min(half + 1e-12, std::numbers::pi)};
}

void AabbTree::Build(const Points& positions, const Triangles& triangles, int leaf_size) {
  GIPSI_CHECK(leaf_size >= 1 && leaf_size <= 8, "leaf size must be in [1, 8]");
  leaf_size_ = leaf_size;
  const auto num = static_cast<std::size_t>(triangles.cols());
  centroid_.resize(num);
  order_.resize(num);
  box_.resize(num);
  for (std::size_t t = 0; t < num; ++t) {
    Box3 b;
    for (int k = 0; k < 3; ++k) b.Add(Vec3(positions.col(triangles(k, static_cast<Index>(t)))));
    centroid_[t] = 0.5 * (b.lo + b.hi);
    order_[t] = static_cast<int>(t);
  }
  nodes_.clear();
  cones_.clear();
  ++num_builds_;
  inner_area_ = built_area_ = 0;
  if (num == 0) return;
  nodes_.reserve(2 * num / static_cast<std::size_t>(leaf_size) + 2);
  nodes_.emplace_back();
  BuildRange(0, 0, static_cast<int>(num));
  // The corners in leaf order: the refit then streams through them instead of gathering
  // triangles in a permuted order.
  corners_.resize(3 * num);
  for (std::size_t p = 0; p < num; ++p)
    for (int k = 0; k < 3; ++k)
      corners_[3 * p + static_cast<std::size_t>(k)] = triangles(k, order_[p]);
  Refit(positions, triangles);
  built_area_ = inner_area_;
}

// Fills the topology of node `self` for order_[begin, end) (Refit computes the boxes); children
// are appended as a pair, so a child's index is always larger than its parent's.
void AabbTree::BuildRange(int self, int begin, int end) {
  const int n = end - begin;
  if (n <= leaf_size_) {
    nodes_[static_cast<std::size_t>(self)].first = begin;
    nodes_[static_cast<std::size_t>(self)].count = n;
    return;
  }
  Box3 cbox;
  for (int i = begin; i < end; ++i)
    cbox.Add(centroid_[static_cast<std::size_t>(order_[static_cast<std::size_t>(i)])]);
  int axis = 0;
  (cbox.hi - cbox.lo).maxCoeff(&axis);
  // Split near the median at a multiple of the leaf size: the left part gets half the leaves
  // (rounded up), all full; only the last leaf of the whole tree can be partly filled.
  const int leaves = (n + leaf_size_ - 1) / leaf_size_;
  const int mid = begin + leaf_size_ * ((leaves + 1) / 2);
  // Ties broken by triangle id so the tree does not depend on the sort's order.
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](int a, int b) {
                     const double ca = centroid_[static_cast<std::size_t>(a)][axis];
                     const double cb = centroid_[static_cast<std::size_t>(b)][axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  const int first = static_cast<int>(nodes_.size());
  nodes_[static_cast<std::size_t>(self)].first = first;
  nodes_[static_cast<std::size_t>(self)].count = 0;
  nodes_.emplace_back();
  nodes_.emplace_back();
  BuildRange(first, begin, mid);
  BuildRange(first + 1, mid, end);
}

void AabbTree::Refit(const Points& positions, const Triangles& triangles) {
  if (nodes_.empty()) return;
  GIPSI_CHECK(triangles.cols() == static_cast<Index>(box_.size()));
  const double* x = positions.data();
  for (std::size_t p = 0; p < box_.size(); ++p) {
    const double* v0 = x + 3 * static_cast<std::ptrdiff_t>(corners_[3 * p]);
    const double* v1 = x + 3 * static_cast<std::ptrdiff_t>(corners_[3 * p + 1]);
    const double* v2 = x + 3 * static_cast<std::ptrdiff_t>(corners_[3 * p + 2]);
    Box3& b = box_[p];
    for (int k = 0; k < 3; ++k) {
      b.lo[k] = std::min(std::min(v0[k], v1[k]), v2[k]);
      b.hi[k] = std::max(std::max(v0[k], v1[k]), v2[k]);
    }
  }
  // Children always have larger indices than their parent: a reverse sweep is bottom-up. The
  // box is accumulated in locals (accumulating into a Box3 on the stack stalled on
  // store-to-load forwarding).
  double inner = 0;
  for (std::size_t i = nodes_.size(); i-- > 0;) {
    Node& n = nodes_[i];
    double lo[3], hi[3];
    if (n.is_leaf()) {
      const Box3* b = &box_[static_cast<std::size_t>(n.first)];
      for (int k = 0; k < 3; ++k) {
        lo[k] = b[0].lo[k];
        hi[k] = b[0].hi[k];
      }
      for (int m = 1; m < n.count; ++m)
        for (int k = 0; k < 3; ++k) {
          lo[k] = std::min(lo[k], b[m].lo[k]);
          hi[k] = std::max(hi[k], b[m].hi[k]);
        }
    } else {
      const Box3& c0 = nodes_[static_cast<std::size_t>(n.first)].box;
      const Box3& c1 = nodes_[static_cast<std::size_t>(n.first) + 1].box;
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(c0.lo[k], c1.lo[k]);
        hi[k] = std::max(c0.hi[k], c1.hi[k]);
      }
    }
    const double ex = hi[0] - lo[0], ey = hi[1] - lo[1], ez = hi[2] - lo[2];
    for (int k = 0; k < 3; ++k) {
      n.box.lo[k] = lo[k];
      n.box.hi[k] = hi[k];
    }
    // Boxes are never inverted here, so this equals Box3::SurfaceArea.
    n.area = 2 * (ex * ey + ey * ez + ez * ex);
    if (!n.is_leaf()) inner += n.area;
  }
  inner_area_ = inner;
}

double AabbTree::quality_ratio() const { return built_area_ > 0 ? inner_area_ / built_area_ : 1.0; }

bool AabbTree::Update(const Points& positions, const Triangles& triangles, double rebuild_ratio) {
  Refit(positions, triangles);
  if (quality_ratio() <= rebuild_ratio) return false;
  Build(positions, triangles, leaf_size_);
  return true;
}

void AabbTree::RefitCones(const std::vector<NormalCone>& triangle_cones) {
  cones_.resize(nodes_.size());
  for (std::size_t i = nodes_.size(); i-- > 0;) {
    const Node& n = nodes_[i];
    if (n.is_leaf()) {
      NormalCone c =
          triangle_cones[static_cast<std::size_t>(order_[static_cast<std::size_t>(n.first)])];
      for (int k = n.first + 1; k < n.first + n.count; ++k)
        c = MergeCones(
            c, triangle_cones[static_cast<std::size_t>(order_[static_cast<std::size_t>(k)])]);
      cones_[i] = c;
    } else {
      cones_[i] = MergeCones(cones_[static_cast<std::size_t>(n.first)],
                             cones_[static_cast<std::size_t>(n.first) + 1]);
    }
  }
}

}  // namespace gipsi
