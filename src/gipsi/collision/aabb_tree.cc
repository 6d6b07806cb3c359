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

void AabbTree::ComputeTriangleBoxes(const Points& positions, const Triangles& tris) {
  for (Index t = 0; t < tris.cols(); ++t) {
    Box3 b;
    for (int k = 0; k < 3; ++k) b.Add(Vec3(positions.col(tris(k, t))));
    tri_box_[static_cast<std::size_t>(t)] = b;
  }
}

void AabbTree::Build(const Points& positions, const Triangles& triangles, int leaf_size) {
  GIPSI_CHECK(leaf_size >= 1);
  leaf_size_ = leaf_size;
  const auto num = static_cast<std::size_t>(triangles.cols());
  tri_box_.resize(num);
  centroid_.resize(num);
  order_.resize(num);
  ComputeTriangleBoxes(positions, triangles);
  for (std::size_t t = 0; t < num; ++t) {
    centroid_[t] = 0.5 * (tri_box_[t].lo + tri_box_[t].hi);
    order_[t] = static_cast<int>(t);
  }
  nodes_.clear();
  cones_.clear();
  ++num_builds_;
  if (num == 0) return;
  nodes_.reserve(2 * num / static_cast<std::size_t>(leaf_size) + 2);
  nodes_.emplace_back();
  BuildRange(0, 0, static_cast<int>(num));
  built_area_ = InnerArea();
}

// Fills node `self` for order_[begin, end); children are appended as a pair, so a child's
// index is always larger than its parent's.
void AabbTree::BuildRange(int self, int begin, int end) {
  Box3 box, cbox;
  for (int i = begin; i < end; ++i) {
    const auto t = static_cast<std::size_t>(order_[static_cast<std::size_t>(i)]);
    box.Add(tri_box_[t]);
    cbox.Add(centroid_[t]);
  }
  nodes_[static_cast<std::size_t>(self)].box = box;
  if (end - begin <= leaf_size_) {
    nodes_[static_cast<std::size_t>(self)].first = begin;
    nodes_[static_cast<std::size_t>(self)].count = end - begin;
    return;
  }
  int axis = 0;
  (cbox.hi - cbox.lo).maxCoeff(&axis);
  const int mid = begin + (end - begin) / 2;
  // Median split; ties broken by triangle id so the tree does not depend on the sort's order.
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
  GIPSI_CHECK(triangles.cols() == static_cast<Index>(tri_box_.size()));
  ComputeTriangleBoxes(positions, triangles);
  // Children always have larger indices than their parent: a reverse sweep is bottom-up.
  for (std::size_t i = nodes_.size(); i-- > 0;) {
    Node& n = nodes_[i];
    Box3 b;
    if (n.is_leaf()) {
      for (int k = n.first; k < n.first + n.count; ++k)
        b.Add(tri_box_[static_cast<std::size_t>(order_[static_cast<std::size_t>(k)])]);
    } else {
      b = nodes_[static_cast<std::size_t>(n.first)].box;
      b.Add(nodes_[static_cast<std::size_t>(n.first) + 1].box);
    }
    n.box = b;
  }
}

double AabbTree::InnerArea() const {
  double area = 0;
  for (const Node& n : nodes_)
    if (!n.is_leaf()) area += n.box.SurfaceArea();
  return area;
}

double AabbTree::quality_ratio() const { return built_area_ > 0 ? InnerArea() / built_area_ : 1.0; }

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
