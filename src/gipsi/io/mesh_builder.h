#pragma once
/// @file
/// Internal helper of the mesh readers: accumulates nodes, tets, triangles and groups in growable
/// arrays, then builds and validates a `Mesh`. Not part of the public API.

#include <algorithm>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::internal {

/// Growable mesh under construction. Movable and copyable (plain data).
struct MeshBuilder {
  std::vector<double> coords;  ///< x0 y0 z0 x1 ...
  std::vector<int> tets;       ///< 4 node indices per tet
  std::vector<int> triangles;  ///< 3 node indices per triangle
  std::vector<MeshGroup> groups;

  [[nodiscard]] int num_nodes() const { return static_cast<int>(coords.size() / 3); }
  [[nodiscard]] int num_tets() const { return static_cast<int>(tets.size() / 4); }
  [[nodiscard]] int num_triangles() const { return static_cast<int>(triangles.size() / 3); }

  /// Appends a node and returns its index.
  int AddNode(double x, double y, double z) {
    coords.push_back(x);
    coords.push_back(y);
    coords.push_back(z);
    return num_nodes() - 1;
  }
  /// Appends a tet and returns its index.
  int AddTet(int a, int b, int c, int d) {
    tets.insert(tets.end(), {a, b, c, d});
    return num_tets() - 1;
  }
  /// Appends a triangle and returns its index.
  int AddTriangle(int a, int b, int c) {
    triangles.insert(triangles.end(), {a, b, c});
    return num_triangles() - 1;
  }

  /// Moves the data into a Mesh and runs `Mesh::Validate(source)` (throws InputError).
  Mesh Build(std::string_view source) {
    Mesh mesh;
    mesh.nodes = Eigen::Map<const Points>(coords.data(), 3, num_nodes());
    mesh.tets = Eigen::Map<const Tets>(tets.data(), 4, num_tets());
    mesh.triangles = Eigen::Map<const Triangles>(triangles.data(), 3, num_triangles());
    mesh.groups = std::move(groups);
    mesh.Validate(source);
    return mesh;
  }
};

/// Adds `group` to `groups`, making its name unique by appending `suffix` (and then a counter)
/// if the name is taken.
inline void AddUniqueGroup(std::vector<MeshGroup>& groups, MeshGroup group,
                           std::string_view suffix) {
  auto taken = [&](const std::string& name) {
    return std::any_of(groups.begin(), groups.end(),
                       [&](const MeshGroup& g) { return g.name == name; });
  };
  if (taken(group.name)) {
    std::string base = group.name + std::string(suffix);
    std::string name = base;
    for (int i = 2; taken(name); ++i) name = base + "_" + std::to_string(i);
    group.name = std::move(name);
  }
  groups.push_back(std::move(group));
}

}  // namespace gipsi::internal
GIPSI_EXPORT_END
