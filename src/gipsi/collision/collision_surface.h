#pragma once
/// @file
/// `CollisionSurface`: one triangle surface as the narrow phase sees it: its current vertex
/// positions, its edges, which triangle *owns* each vertex and each edge (so every feature is
/// tested once even though several triangles share it), per-step normals, and its AABB tree.

#include <cstdint>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/collision/aabb_tree.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable (holds a tree over its own triangles); movable.
class CollisionSurface {
 public:
  /// `triangles` 3 by T over `num_vertices` vertices. `closed`: the surface bounds a volume
  /// and its triangles are oriented outward (signed distances are then meaningful). Vertices
  /// used by no triangle have no owner and never collide.
  CollisionSurface(Triangles triangles, Index num_vertices, bool closed);
  CollisionSurface(CollisionSurface&&) = default;
  CollisionSurface& operator=(CollisionSurface&&) = default;
  CollisionSurface(const CollisionSurface&) = delete;
  CollisionSurface& operator=(const CollisionSurface&) = delete;

  /// Writable current positions, 3 by V (set them, then call Update).
  [[nodiscard]] Points& positions() { return positions_; }
  [[nodiscard]] const Points& positions() const { return positions_; }
  /// Refits the tree (building it the first time; rebuilding when its quality ratio exceeds
  /// `rebuild_ratio`) and recomputes face normals; with `cones`, also vertex and edge normals
  /// and the tree's normal cones (needed for self-collision). Allocation-free after the first
  /// call, except when the tree is rebuilt.
  void Update(double rebuild_ratio, bool cones);

  [[nodiscard]] Index num_vertices() const { return positions_.cols(); }
  [[nodiscard]] Index num_triangles() const { return triangles_.cols(); }
  [[nodiscard]] Index num_edges() const { return edges_.cols(); }
  [[nodiscard]] bool closed() const { return closed_; }
  [[nodiscard]] const Triangles& triangles() const { return triangles_; }
  /// 2 by E vertex pairs (smaller index first), sorted.
  [[nodiscard]] const Eigen::Matrix2Xi& edges() const { return edges_; }
  /// 3 by T: edge k of triangle t joins its vertices k and (k+1) mod 3.
  [[nodiscard]] const Triangles& triangle_edges() const { return tri_edges_; }
  /// Owning triangle of each vertex (−1 if none) and of each edge: the lowest triangle id.
  [[nodiscard]] const std::vector<int>& vertex_owner() const { return vertex_owner_; }
  [[nodiscard]] const std::vector<int>& edge_owner() const { return edge_owner_; }
  /// The same ownership per triangle as a bit mask: bit k (k = 0, 1, 2) is set if triangle t
  /// owns its vertex k, bit 3 + k if it owns its edge k (see `triangle_edges`).
  [[nodiscard]] const std::vector<std::uint8_t>& owned_features() const { return owned_; }
  /// Unit outward normals at the last Update (3 by T); vertex and edge normals (angle-free
  /// area-weighted means of the incident faces) only when Update ran with cones.
  [[nodiscard]] const Points& face_normals() const { return face_normals_; }
  [[nodiscard]] const Points& vertex_normals() const { return vertex_normals_; }
  [[nodiscard]] const Points& edge_normals() const { return edge_normals_; }
  [[nodiscard]] const AabbTree& tree() const { return tree_; }
  /// Box of all vertices at the last Update.
  [[nodiscard]] const Box3& bounds() const;

 private:
  Triangles triangles_;
  Eigen::Matrix2Xi edges_;
  Triangles tri_edges_;
  std::vector<int> vertex_owner_, edge_owner_;
  std::vector<std::uint8_t> owned_;
  bool closed_ = false;
  Points positions_;
  Points face_normals_, vertex_normals_, edge_normals_;
  std::vector<NormalCone> tri_cones_;
  AabbTree tree_;
  Box3 empty_box_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
