#pragma once
/// @file
/// `AabbTree`: a bounding-volume hierarchy of axis-aligned boxes over the triangles of a
/// deforming surface. Built once by splitting the triangle centroids along the longest axis
/// near the median, at a multiple of the leaf size, so every leaf but the last holds exactly
/// `leaf_size` triangles (fixed-size leaves keep the leaf loops of the queries predictable);
/// refitted bottom-up every step in one pass over a flat array (O(T)); rebuilt when refitting
/// has let the boxes grow too much (the summed surface area of the inner boxes exceeds
/// `rebuild_ratio` times its value right after the last build). Triangle boxes are stored in
/// leaf order, so a leaf's boxes are contiguous. Optionally keeps a normal cone per node for
/// self-collision culling.

#include <cstdint>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A box, min and max corners. Plain struct.
struct Box3 {
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  void Add(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void Add(const Box3& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  /// True if the boxes are within `gap` of each other along every axis (so points of the two
  /// boxes closer than `gap` in Euclidean distance are never missed).
  [[nodiscard]] bool Near(const Box3& b, double gap) const {
    // The six comparisons are combined without branches (`&`, not `&&`): one (often
    // unpredictable) branch for the caller instead of up to six. The results of the box tests
    // in the queries are close to random, and mispredicted branches were half of the query's
    // time. With SSE2 (every x86-64) two axes at a time; the same operations, same results.
#if defined(__SSE2__)
    const __m128d g = _mm_set1_pd(gap);
    const __m128d xy =
        _mm_and_pd(_mm_cmple_pd(_mm_sub_pd(_mm_loadu_pd(lo.data()), g), _mm_loadu_pd(b.hi.data())),
                   _mm_cmple_pd(_mm_sub_pd(_mm_loadu_pd(b.lo.data()), g), _mm_loadu_pd(hi.data())));
    const __m128d z =
        _mm_cmple_pd(_mm_sub_pd(_mm_set_pd(b.lo[2], lo[2]), g), _mm_set_pd(hi[2], b.hi[2]));
    return _mm_movemask_pd(_mm_and_pd(xy, z)) == 3;
#else
    return (int(lo[0] - gap <= b.hi[0]) & int(b.lo[0] - gap <= hi[0]) &
            int(lo[1] - gap <= b.hi[1]) & int(b.lo[1] - gap <= hi[1]) &
            int(lo[2] - gap <= b.hi[2]) & int(b.lo[2] - gap <= hi[2])) != 0;
#endif
  }
  /// True if point p is within `gap` of the box along every axis. Branch-free like Near.
  [[nodiscard]] bool NearPoint(const Vec3& p, double gap) const {
    // The comparisons as ints: `&` between bools is what clang warns of as a likely `&&`.
    return (int(p[0] >= lo[0] - gap) & int(p[0] <= hi[0] + gap) & int(p[1] >= lo[1] - gap) &
            int(p[1] <= hi[1] + gap) & int(p[2] >= lo[2] - gap) & int(p[2] <= hi[2] + gap)) != 0;
  }
  [[nodiscard]] double SurfaceArea() const {
    const Vec3 e = (hi - lo).cwiseMax(0.0);
    return 2 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
  }
};

/// A cone of unit directions: every direction n in it has n · axis >= cos(half_angle).
/// Plain struct.
struct NormalCone {
  Vec3 axis = Vec3::UnitZ();
  double half_angle = 0;  ///< radians, in [0, π]
};

/// Not copyable (large); movable.
class AabbTree {
 public:
  /// One node: a box, its surface area (at the last refit; the traversals descend the larger
  /// node of a pair), and either two children (`first` and `first + 1`) or a range of
  /// triangles [first, first + count) of `order()` (a leaf has count > 0). 64 bytes: one cache
  /// line.
  struct Node {
    Box3 box;
    double area = 0;
    int first = 0;
    int count = 0;
    [[nodiscard]] bool is_leaf() const { return count > 0; }
  };

  AabbTree() = default;
  AabbTree(AabbTree&&) = default;
  AabbTree& operator=(AabbTree&&) = default;
  AabbTree(const AabbTree&) = delete;
  AabbTree& operator=(const AabbTree&) = delete;

  /// Builds over `triangles` (3 by T) with vertices `positions` (3 by V). Leaves hold at most
  /// `leaf_size` triangles, in [1, 8] (the queries test two leaves as one 64-bit mask).
  void Build(const Points& positions, const Triangles& triangles, int leaf_size = 4);
  /// Recomputes every box from `positions` bottom-up, keeping the topology. Allocation-free.
  /// `triangles` must be those of the last Build (the tree keeps no reference to them).
  void Refit(const Points& positions, const Triangles& triangles);
  /// Refit, then rebuild if the inner boxes' summed area exceeds `rebuild_ratio` (> 1) times its
  /// value after the last build. Returns true if it rebuilt.
  bool Update(const Points& positions, const Triangles& triangles, double rebuild_ratio);
  /// Recomputes the normal cones bottom-up from per-triangle cones (`triangle_cones`, size T:
  /// each cone must contain every normal the caller associates with that triangle).
  void RefitCones(const std::vector<NormalCone>& triangle_cones);

  [[nodiscard]] const std::vector<Node>& nodes() const { return nodes_; }
  /// Triangle ids in leaf order.
  [[nodiscard]] const std::vector<int>& order() const { return order_; }
  /// Box at the last refit of the triangle at position p of `order()` (leaf order).
  [[nodiscard]] const Box3& ordered_box(int p) const { return box_[static_cast<std::size_t>(p)]; }
  /// All triangle boxes in leaf order.
  [[nodiscard]] const std::vector<Box3>& ordered_boxes() const { return box_; }
  /// Most triangles in a leaf (every leaf but the last in leaf order holds exactly this many).
  [[nodiscard]] int leaf_size() const { return leaf_size_; }
  [[nodiscard]] const NormalCone& cone(int node) const {
    return cones_[static_cast<std::size_t>(node)];
  }
  [[nodiscard]] bool has_cones() const { return !cones_.empty(); }
  [[nodiscard]] int num_builds() const { return num_builds_; }
  [[nodiscard]] bool empty() const { return nodes_.empty(); }
  /// Summed surface area of inner boxes now / right after the last build (1 after a build).
  [[nodiscard]] double quality_ratio() const;

 private:
  void BuildRange(int self, int begin, int end);

  std::vector<Node> nodes_;
  std::vector<int> order_;
  std::vector<Box3> box_;       // triangle boxes in leaf order
  std::vector<int> corners_;    // vertex ids of the triangles in leaf order, 3 per triangle
  std::vector<Vec3> centroid_;  // build scratch, by triangle id
  std::vector<NormalCone> cones_;
  double inner_area_ = 0;  // at the last refit
  double built_area_ = 0;
  int num_builds_ = 0;
  int leaf_size_ = 4;
};

/// The smallest cone (approximately: axis = normalised mean) containing cones a and b.
NormalCone MergeCones(const NormalCone& a, const NormalCone& b);

}  // namespace gipsi
GIPSI_EXPORT_END
