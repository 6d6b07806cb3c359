#pragma once
/// @file
/// Boundary geometry: the triangle surface through which an object couples and collides.

#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A triangle surface whose vertices are a subset of a domain's nodes.
/// Plain data: copyable and movable.
struct BoundarySurface {
  /// 3 by T triangles in *boundary-vertex* numbering, oriented so that the right-hand normal
  /// points out of the domain.
  Triangles triangles = Triangles(3, 0);
  /// Domain node of each boundary vertex (size V, strictly increasing).
  std::vector<int> vertex_to_node;
  /// Tetrahedron each boundary triangle belongs to; -1 when the domain is itself a surface.
  std::vector<int> face_to_tet;

  [[nodiscard]] Index num_vertices() const { return Index(vertex_to_node.size()); }
  [[nodiscard]] Index num_triangles() const { return triangles.cols(); }
  /// Gathers the positions of the boundary vertices from domain positions (3 by N) into
  /// `out` (3 by V). Allocation-free when `out` already has the right size.
  void Gather(const Points& domain_positions, Points& out) const;
};

/// The boundary of a tetrahedral mesh: every face that belongs to exactly one tetrahedron,
/// oriented outward (using the geometry of `nodes`, so negatively oriented tets are handled).
/// Nodes not on the boundary do not appear. `nodes` is 3 by N, `tets` 4 by E.
BoundarySurface ExtractTetBoundary(const Points& nodes, const Tets& tets);

/// The boundary geometry of a mesh: for a mesh with tets, `ExtractTetBoundary`; for a
/// triangle-only mesh, the triangles themselves (with the nodes they use) as the boundary.
/// Throws InputError if the mesh has neither tets nor triangles.
BoundarySurface MakeBoundary(const Mesh& mesh);

}  // namespace gipsi
GIPSI_EXPORT_END
