#include "gipsi/geometry/region.h"

#include <algorithm>
#include <array>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi {
namespace {

/// Relative tolerance of geometric region tests, times the mesh bounding-box diagonal.
constexpr double kRelativeTolerance = 1e-9;

double Tolerance(const Mesh& mesh) {
  if (mesh.num_nodes() == 0) return 0;
  return RegionTolerance(mesh.nodes.rowwise().minCoeff(), mesh.nodes.rowwise().maxCoeff());
}

template <class Inside>
std::vector<int> SelectWhere(const Mesh& mesh, Inside&& inside) {
  std::vector<int> ids;
  for (Index n = 0; n < mesh.num_nodes(); ++n)
    if (inside(Vec3(mesh.nodes.col(n)))) ids.push_back(int(n));
  return ids;
}

void SortUnique(std::vector<int>& ids) {
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
}

const MeshGroup& FindGroupOrThrow(const Mesh& mesh, const std::string& name) {
  if (const MeshGroup* group = mesh.FindGroup(name)) return *group;
  std::string names;
  for (const auto& g : mesh.groups)
    names += fmt::format("{}'{}'", names.empty() ? "" : ", ", g.name);
  ThrowInputError("", fmt::format("group region '{}'", name),
                  fmt::format("no mesh group of that name; available groups: {}",
                              names.empty() ? "(none)" : names));
}

std::vector<int> GroupNodes(const Mesh& mesh, const MeshGroup& group) {
  std::vector<int> ids;
  if (group.dim == 0) {
    ids = group.items;
  } else {
    auto collect = [&](const auto& conn) {
      ids.reserve(group.items.size() * std::size_t(conn.rows()));
      for (int item : group.items)
        for (Index a = 0; a < conn.rows(); ++a) ids.push_back(conn(a, item));
    };
    if (group.dim == 2)
      collect(mesh.triangles);
    else
      collect(mesh.tets);
  }
  SortUnique(ids);
  return ids;
}

std::vector<int> Select(const AllRegion&, const Mesh& mesh, double) {
  std::vector<int> ids(std::size_t(mesh.num_nodes()));
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = int(i);
  return ids;
}

std::vector<int> Select(const BoxRegion& box, const Mesh& mesh, double tol) {
  return SelectWhere(mesh, [&](const Vec3& x) {
    return (x.array() >= box.min.array() - tol).all() && (x.array() <= box.max.array() + tol).all();
  });
}

std::vector<int> Select(const HalfSpaceRegion& half, const Mesh& mesh, double tol) {
  const double length = half.normal.norm();
  if (!(length > 0) || !half.normal.allFinite())
    ThrowInputError("", "half-space region", "normal must be a finite non-zero vector");
  const Vec3 n = half.normal / length;
  return SelectWhere(mesh, [&](const Vec3& x) { return (x - half.point).dot(n) >= -tol; });
}

std::vector<int> Select(const SphereRegion& sphere, const Mesh& mesh, double tol) {
  if (!(sphere.radius >= 0))
    ThrowInputError("", "sphere region",
                    fmt::format("radius must be non-negative, got {}", sphere.radius));
  const double limit = sphere.radius + tol;
  return SelectWhere(mesh, [&](const Vec3& x) { return (x - sphere.center).norm() <= limit; });
}

std::vector<int> Select(const GroupRegion& group, const Mesh& mesh, double) {
  return GroupNodes(mesh, FindGroupOrThrow(mesh, group.name));
}

std::vector<int> Select(const NodeIdsRegion& region, const Mesh& mesh, double) {
  for (std::size_t i = 0; i < region.ids.size(); ++i) {
    const int id = region.ids[i];
    if (id < 0 || id >= mesh.num_nodes())
      ThrowInputError("", fmt::format("node id region: ids[{}]", i),
                      fmt::format("node id {} out of range [0, {})", id, mesh.num_nodes()));
  }
  std::vector<int> ids = region.ids;
  SortUnique(ids);
  return ids;
}

}  // namespace

double RegionTolerance(const Vec3& low, const Vec3& high) {
  return kRelativeTolerance * (high - low).norm();
}

std::vector<int> SelectNodes(const Region& region, const Mesh& mesh, double tolerance) {
  return std::visit([&](const auto& r) { return Select(r, mesh, tolerance); }, region);
}

std::vector<int> SelectNodes(const Region& region, const Mesh& mesh) {
  return SelectNodes(region, mesh, Tolerance(mesh));
}

std::vector<int> SelectBoundaryVertices(const Region& region, const Mesh& mesh,
                                        const BoundarySurface& boundary) {
  const std::vector<int> nodes = SelectNodes(region, mesh);
  // Both lists are increasing: merge.
  std::vector<int> vertices;
  std::size_t i = 0;
  for (Index v = 0; v < boundary.num_vertices(); ++v) {
    const int node = boundary.vertex_to_node[std::size_t(v)];
    while (i < nodes.size() && nodes[i] < node) ++i;
    if (i == nodes.size()) break;
    if (nodes[i] == node) vertices.push_back(int(v));
  }
  return vertices;
}

std::vector<int> SelectBoundaryFaces(const Region& region, const Mesh& mesh,
                                     const BoundarySurface& boundary) {
  std::vector<int> faces;
  const auto* group_region = std::get_if<GroupRegion>(&region);
  if (group_region != nullptr) {
    const MeshGroup& group = FindGroupOrThrow(mesh, group_region->name);
    if (group.dim == 2) {
      // Match the group's triangles to boundary triangles by their sorted node triples.
      using Key = std::array<int, 3>;
      auto sorted_nodes = [](int a, int b, int c) {
        Key key{a, b, c};
        std::sort(key.begin(), key.end());
        return key;
      };
      std::vector<std::pair<Key, int>> keys;
      keys.reserve(std::size_t(boundary.num_triangles()));
      for (Index t = 0; t < boundary.num_triangles(); ++t) {
        const auto& v2n = boundary.vertex_to_node;
        keys.emplace_back(sorted_nodes(v2n[std::size_t(boundary.triangles(0, t))],
                                       v2n[std::size_t(boundary.triangles(1, t))],
                                       v2n[std::size_t(boundary.triangles(2, t))]),
                          int(t));
      }
      std::sort(keys.begin(), keys.end());
      for (int item : group.items) {
        const Key key =
            sorted_nodes(mesh.triangles(0, item), mesh.triangles(1, item), mesh.triangles(2, item));
        auto it = std::lower_bound(keys.begin(), keys.end(), std::make_pair(key, -1));
        for (; it != keys.end() && it->first == key; ++it) faces.push_back(it->second);
      }
      SortUnique(faces);
      return faces;
    }
  }
  std::vector<char> selected(std::size_t(boundary.num_vertices()), 0);
  for (int v : SelectBoundaryVertices(region, mesh, boundary)) selected[std::size_t(v)] = 1;
  for (Index t = 0; t < boundary.num_triangles(); ++t) {
    if (selected[std::size_t(boundary.triangles(0, t))] &&
        selected[std::size_t(boundary.triangles(1, t))] &&
        selected[std::size_t(boundary.triangles(2, t))])
      faces.push_back(int(t));
  }
  return faces;
}

}  // namespace gipsi
