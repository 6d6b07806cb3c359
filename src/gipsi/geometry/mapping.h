#pragma once
/// @file
/// Mappings between geometries: values known at the nodes of a source geometry interpolated at
/// target points. Used for display geometries embedded in a domain (barycentric embedding), for
/// probes at points, and by connectors between objects on different meshes.

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Fixed interpolation weights: target j gets Σ_k weights(k, j) · source[indices(k, j)], with up
/// to four sources per target (unused slots have weight 0 and index 0). Built once, applied
/// every step without allocating. Copyable and movable.
class PointMap {
 public:
  PointMap() = default;

  /// Barycentric embedding in a tet mesh (`nodes` 3 by N, `tets` 4 by E): each target uses the
  /// tet containing it; a target outside the mesh uses the nearest tet with its barycentric
  /// coordinates clamped to the tet (and `max_distance()` reports how far off it was).
  /// Candidate tets come from a uniform grid of tet bounding boxes (no search over all tets).
  /// Throws InputError if there are targets but no tets, or a target is not finite.
  static PointMap BarycentricInTets(const Points& nodes, const Tets& tets, const Points& targets);

  /// Barycentric on a triangle surface: the closest point on any triangle (Ericson, Real-Time
  /// Collision Detection, §5.1.5). Throws InputError if there are targets but no triangles, or
  /// a target is not finite.
  static PointMap BarycentricOnTriangles(const Points& vertices, const Triangles& triangles,
                                         const Points& targets);

  /// Nearest source point (weight 1). Throws InputError if there are targets but no sources,
  /// or a target is not finite.
  static PointMap Nearest(const Points& sources, const Points& targets);
  /// Given weights: target j gets Σ_k weights(k, j) · source[indices(k, j)]. `max_distance` as
  /// max_distance(). Shapes must agree (checked).
  static PointMap FromWeights(Eigen::Matrix4Xi indices, Eigen::Matrix4Xd weights,
                              double max_distance);

  [[nodiscard]] Index num_targets() const { return indices_.cols(); }
  [[nodiscard]] const Eigen::Matrix4Xi& indices() const { return indices_; }
  [[nodiscard]] const Eigen::Matrix4Xd& weights() const { return weights_; }
  /// Largest distance between a target and the point its weights reproduce at build time.
  [[nodiscard]] double max_distance() const { return max_distance_; }

  /// out.col(j) = Σ_k w(k,j) · source.col(idx(k,j)). `source` is C by N_source, `out` C by
  /// num_targets() (preconditions checked). Allocates nothing.
  void Apply(const Eigen::Ref<const Eigen::MatrixXd>& source,
             Eigen::Ref<Eigen::MatrixXd> out) const;
  /// Apply, except that a target component whose weights touch a source item holding `marker`
  /// (a field's no-data value, FieldInfo::no_data) reads `marker` instead of a blend with it.
  void ApplyMarked(const Eigen::Ref<const Eigen::MatrixXd>& source, Eigen::Ref<Eigen::MatrixXd> out,
                   double marker) const;

 private:
  Eigen::Matrix4Xi indices_ = Eigen::Matrix4Xi(4, 0);
  Eigen::Matrix4Xd weights_ = Eigen::Matrix4Xd(4, 0);
  double max_distance_ = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
