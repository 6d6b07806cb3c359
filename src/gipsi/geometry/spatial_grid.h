#pragma once
/// @file
/// `SpatialGrid`: a uniform grid of cells over the bounding boxes of items (points, triangles,
/// tetrahedra), for "which items may contain this point" and "which item is nearest" queries
/// in O(1) expected time per query instead of O(items). Used by mappings and regions at build
/// time; the queries allocate nothing.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Uniform grid over K axis-aligned item boxes. Each item is listed in every cell its box
/// touches (compressed row storage). The cell size is chosen so that there are about as many
/// cells as items, and no smaller than the mean item box size, so an item touches few cells.
/// Immutable after construction; copyable and movable.
class SpatialGrid {
 public:
  SpatialGrid() = default;

  /// Builds the grid over boxes [box_min.col(k), box_max.col(k)] (both 3 by K, min <= max).
  SpatialGrid(const Points& box_min, const Points& box_max);

  [[nodiscard]] Index num_items() const { return num_items_; }
  [[nodiscard]] const std::array<int, 3>& dims() const { return dims_; }

  /// Calls `visit(item)` for every item whose box touches the cell containing `p`. Does
  /// nothing when `p` is outside the grid. (An item may be visited by several cells, but only
  /// once per call here since one cell is visited.)
  template <class Visit>
  void ForEachInCell(const Vec3& p, Visit&& visit) const {
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a) {
      const double t = (p[a] - origin_[a]) / cell_size_[a];
      if (!(t >= 0) || t > dims_[a]) return;  // outside (or NaN)
      c[a] = std::min(static_cast<int>(t), dims_[a] - 1);
    }
    const int cell = CellIndex(c);
    for (int s = cell_start_[cell]; s < cell_start_[cell + 1]; ++s) visit(cell_items_[s]);
  }

  /// The item minimising `distance(item)` (a function returning the exact distance from the
  /// query point `p` to the item, >= the distance from `p` to the item's box; items whose box
  /// is farther than the best item so far are skipped), or -1 when the grid is empty. Searches
  /// rings of cells around `p` until no unvisited item can be closer. Writes the best distance to
  /// `best_distance`.
  template <class Distance>
  int FindNearest(const Vec3& p, Distance&& distance, double& best_distance) const {
    best_distance = std::numeric_limits<double>::infinity();
    if (num_items_ == 0) return -1;
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a) {
      const double t = (p[a] - origin_[a]) / cell_size_[a];
      c[a] = !(t > 0) ? 0 : static_cast<int>(std::min(t, double(dims_[a] - 1)));
    }
    int best = -1;
    const int max_ring = std::max({dims_[0], dims_[1], dims_[2]});
    for (int r = 0; r <= max_ring; ++r) {
      VisitRing(c, r, [&](int item) {
        // Skip items whose box is already farther than the best item (cheap pruning; this
        // also skips repeated visits of an item listed in several cells).
        if (BoxDistance(p, item) > best_distance) return;
        const double d = distance(item);
        if (d < best_distance || (d == best_distance && item < best)) {
          best_distance = d;
          best = item;
        }
      });
      // Strictly nearer than any later ring: an item there as near as the best may have a lower
      // index, which a tie goes to.
      if (best >= 0 && best_distance < RingLowerBound(p, c, r)) break;
    }
    return best;
  }

 private:
  [[nodiscard]] int CellIndex(const std::array<int, 3>& c) const {
    return c[0] + dims_[0] * (c[1] + dims_[1] * c[2]);
  }

  /// Distance from p to the box of `item`.
  [[nodiscard]] double BoxDistance(const Vec3& p, int item) const {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double gap = std::max({box_min_(a, item) - p[a], 0.0, p[a] - box_max_(a, item)});
      d2 += gap * gap;
    }
    return std::sqrt(d2);
  }

  /// Visits the items of every cell at Chebyshev distance exactly `r` from cell `c`.
  template <class Visit>
  void VisitRing(const std::array<int, 3>& c, int r, Visit&& visit) const {
    const int k0 = std::max(c[2] - r, 0), k1 = std::min(c[2] + r, dims_[2] - 1);
    const int j0 = std::max(c[1] - r, 0), j1 = std::min(c[1] + r, dims_[1] - 1);
    const int i0 = std::max(c[0] - r, 0), i1 = std::min(c[0] + r, dims_[0] - 1);
    auto visit_cell = [&](int i, int j, int k) {
      const int cell = CellIndex({i, j, k});
      for (int s = cell_start_[cell]; s < cell_start_[cell + 1]; ++s) visit(cell_items_[s]);
    };
    for (int k = k0; k <= k1; ++k) {
      const bool k_shell = std::abs(k - c[2]) == r;
      for (int j = j0; j <= j1; ++j) {
        if (k_shell || std::abs(j - c[1]) == r) {
          for (int i = i0; i <= i1; ++i) visit_cell(i, j, k);
        } else {  // inside the shell only the two end cells of the row are at distance r
          if (c[0] - r >= 0) visit_cell(c[0] - r, j, k);
          if (r > 0 && c[0] + r < dims_[0]) visit_cell(c[0] + r, j, k);
        }
      }
    }
  }

  /// A lower bound of the distance from `p` to any point of the grid outside the block of
  /// cells within Chebyshev distance `r` of cell `c` (infinity when the block covers the grid).
  /// The region beyond one side of the block along axis a is a slab of the grid box, so the
  /// bound for that side combines the gap along a with the gaps to the grid box along the
  /// other axes.
  [[nodiscard]] double RingLowerBound(const Vec3& p, const std::array<int, 3>& c, int r) const {
    Vec3 outside;  // gap between p and the grid box along each axis
    for (int a = 0; a < 3; ++a) {
      const double hi = origin_[a] + dims_[a] * cell_size_[a];
      outside[a] = std::max({0.0, origin_[a] - p[a], p[a] - hi});
    }
    const double outside2 = outside.squaredNorm();
    double bound2 = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      const double others2 = outside2 - outside[a] * outside[a];
      if (c[a] - r > 0) {
        const double gap = std::max(0.0, p[a] - (origin_[a] + (c[a] - r) * cell_size_[a]));
        bound2 = std::min(bound2, gap * gap + others2);
      }
      if (c[a] + r < dims_[a] - 1) {
        const double gap = std::max(0.0, origin_[a] + (c[a] + r + 1) * cell_size_[a] - p[a]);
        bound2 = std::min(bound2, gap * gap + others2);
      }
    }
    return std::sqrt(bound2);
  }

  Index num_items_ = 0;
  Vec3 origin_ = Vec3::Zero();
  Vec3 cell_size_ = Vec3::Ones();
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<int> cell_start_{0, 0};  ///< size num_cells + 1
  std::vector<int> cell_items_;
  Points box_min_ = Points(3, 0), box_max_ = Points(3, 0);  ///< 3 by K item boxes
};

}  // namespace gipsi
GIPSI_EXPORT_END
