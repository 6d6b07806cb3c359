#pragma once
/// @file
/// `Mesh`: the immutable geometric asset every reader and generator produces and every simulation
/// object is built on: nodes, tetrahedra and/or triangles, and named groups (Gmsh physical
/// groups, VTK/TetGen region markers). Shared between objects as `std::shared_ptr<const Mesh>`.

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A named subset of a mesh (a Gmsh physical group, a TetGen/VTK region or boundary marker).
struct MeshGroup {
  std::string name;
  /// 0: `items` are node indices; 2: triangle indices; 3: tet indices.
  int dim = 0;
  std::vector<int> items;
};

/// Gmsh's local order of the edges whose middle nodes follow the corners of a second-order
/// element: nodes 4..9 of a 10-node tet, and (the first three) nodes 3..5 of a 6-node triangle.
inline constexpr int kGmshSecondOrderEdges[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {2, 3}, {1, 3}};

/// Nodes plus tetrahedra and/or triangles. Both connectivity blocks may be present (a tet mesh
/// with tagged boundary triangles, as Gmsh writes them). Plain data: copyable and movable.
struct Mesh {
  Points nodes = Points(3, 0);            ///< 3 by N node coordinates (scene units)
  Tets tets = Tets(4, 0);                 ///< 4 by E node indices of each tetrahedron
  Triangles triangles = Triangles(3, 0);  ///< 3 by T node indices of each triangle
  std::vector<MeshGroup> groups;          ///< named groups, unique names
  /// The mesh file's own id of each tet (Gmsh element tags), and what the ids are (singular,
  /// e.g. "Gmsh element tag"); empty for generated meshes and formats without ids, whose tets
  /// are named by their 0-based index. Messages name tets through TetName.
  std::vector<std::int64_t> tet_ids;
  std::string tet_id_kind;
  /// Second-order (curved) geometry, from files with 10-node tets or 6-node triangles (Gmsh
  /// types 11 and 9): column k of `edge_nodes` is the position of the node in the middle of
  /// the edge between nodes `edge_node_ends(0, k)` < `edge_node_ends(1, k)`. Those middle nodes
  /// are not in `nodes`, so every object on linear elements sees the mesh of the corners;
  /// quadratic elements (MixedSolid) take their edge nodes from here, where the edges curve.
  /// Empty for linear meshes.
  Eigen::Matrix2Xi edge_node_ends = Eigen::Matrix2Xi(2, 0);
  Points edge_nodes = Points(3, 0);

  [[nodiscard]] Index num_nodes() const { return nodes.cols(); }
  [[nodiscard]] Index num_tets() const { return tets.cols(); }
  [[nodiscard]] Index num_triangles() const { return triangles.cols(); }

  /// Tet e's id: its id in the mesh file, or e without file ids.
  [[nodiscard]] std::int64_t TetId(Index e) const {
    return tet_ids.empty() ? e : tet_ids[static_cast<std::size_t>(e)];
  }
  /// What TetId is, for messages: "Gmsh element tag" or "0-based index".
  [[nodiscard]] std::string_view TetIdKind() const {
    return tet_ids.empty() ? std::string_view("0-based index") : std::string_view(tet_id_kind);
  }
  /// Tet e as messages name it: "tet 813 (Gmsh element tag)" or "tet 12 (0-based index)".
  [[nodiscard]] std::string TetName(Index e) const;
  /// The ids of the first ten of `tets` and what they are, for messages: "9, 12 (Gmsh element
  /// tags)", "3, 7, ... (5 more) (0-based indices in file order)".
  [[nodiscard]] std::string TetIdList(const std::vector<int>& tets) const;

  /// The group called `name`, or nullptr.
  [[nodiscard]] const MeshGroup* FindGroup(std::string_view name) const;

  /// Throws InputError (naming `source`) unless: coordinates are finite, every index is in
  /// range, no element repeats a node, every group refers to existing items, and tet_ids is
  /// empty or has one id per tet.
  void Validate(std::string_view source) const;

  /// Drops nodes no element refers to (keeps all when there are no elements) and renumbers
  /// connectivity, node groups and `edge_node_ends`. Returns the old index of each kept node.
  std::vector<int> RemoveUnusedNodes();
  /// Keeps the nodes with `keep[i]` true (`keep` has one entry per node; elements must not
  /// refer to the others), renumbering as RemoveUnusedNodes; node groups and second-order edges
  /// lose the dropped nodes. Returns the old index of each kept node.
  std::vector<int> KeepNodes(const std::vector<std::uint8_t>& keep);
  /// For second-order input read as linear elements on the corners: `middle_of_edge` maps each
  /// edge (key min·2³² + max of its end nodes) to the node in its middle. Sets `edge_nodes` and
  /// `edge_node_ends` from them and drops those nodes (but not one that is also an element's
  /// corner), renumbering as KeepNodes.
  void SeparateEdgeNodes(const std::map<std::uint64_t, int>& middle_of_edge);
  /// Scales, then translates, every position (nodes and second-order edge nodes).
  void Transform(double scale, const Vec3& translate);
};

}  // namespace gipsi
GIPSI_EXPORT_END
