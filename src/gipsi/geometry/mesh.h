#pragma once
/// @file
/// `Mesh`: the immutable geometric asset every reader and generator produces and every simulation
/// object is built on: nodes, tetrahedra and/or triangles, and named groups (Gmsh physical
/// groups, VTK/TetGen region markers). Shared between objects as `std::shared_ptr<const Mesh>`.

#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/math.h"

namespace gipsi {

/// A named subset of a mesh (a Gmsh physical group, a TetGen/VTK region or boundary marker).
struct MeshGroup {
  std::string name;
  /// 0: `items` are node indices; 2: triangle indices; 3: tet indices.
  int dim = 0;
  std::vector<int> items;
};

/// Nodes plus tetrahedra and/or triangles. Both connectivity blocks may be present (a tet mesh
/// with tagged boundary triangles, as Gmsh writes them). Plain data: copyable and movable.
struct Mesh {
  Points nodes = Points(3, 0);            ///< 3 by N node coordinates (scene units)
  Tets tets = Tets(4, 0);                 ///< 4 by E node indices of each tetrahedron
  Triangles triangles = Triangles(3, 0);  ///< 3 by T node indices of each triangle
  std::vector<MeshGroup> groups;          ///< named groups, unique names

  [[nodiscard]] Index num_nodes() const { return nodes.cols(); }
  [[nodiscard]] Index num_tets() const { return tets.cols(); }
  [[nodiscard]] Index num_triangles() const { return triangles.cols(); }

  /// The group called `name`, or nullptr.
  [[nodiscard]] const MeshGroup* FindGroup(std::string_view name) const;

  /// Throws InputError (naming `source`) unless: coordinates are finite, every index is in
  /// range, no element repeats a node, every group refers to existing items.
  void Validate(std::string_view source) const;

  /// Drops nodes no element refers to (keeps all when there are no elements) and renumbers
  /// connectivity and node groups. Returns the old index of each kept node.
  std::vector<int> RemoveUnusedNodes();
};

}  // namespace gipsi
