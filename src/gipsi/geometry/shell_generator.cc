/// @file
/// `MakeEllipsoidShell`, `MakeCylinderShell` and `MakeTetsInSurface` through the Gmsh C++ API with
/// the OpenCASCADE kernel (Debian's libgmsh 4.8 is built with it): solids are made by boolean cuts,
/// meshed in 3-D, and read back as nodes and linear tets. The boundary is then extracted from the
/// tets
/// (`ExtractTetBoundary`, so it is closed and outward) and its triangles are grouped by where
/// they lie (base plane, inner or outer surface) instead of by Gmsh entity tags, which would
/// depend on the numbering OpenCASCADE gives the faces after the cuts.
///
/// Gmsh keeps global state, so every use goes through `GmshSession`: a process-wide mutex held
/// from `gmsh::initialize` to `gmsh::finalize`.
///
/// `gmsh::initialize` sets the calling thread's OpenMP team size to its General.NumThreads (1)
/// with `omp_set_num_threads`, and `gmsh::finalize` leaves it there: before the session restored
/// it, every scene that generated a mesh (the heart demo among them) then ran all of GiPSi's
/// parallel loops on one thread, whatever OMP_NUM_THREADS said.

#include <gmsh.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <clocale>
#include <cmath>
#include <cstdint>
#include <functional>
#include <mutex>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/edge_key.h"
#include "gipsi/geometry/enclosed_volume.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/quality.h"

namespace gipsi {
namespace {

/// Gmsh element type of the 4-node tetrahedron.
constexpr int kGmshTet4 = 4;
constexpr int kGmshTet10 = 11;
/// Refuse to mesh when the estimated number of tets exceeds this (a too small mesh size).
constexpr double kMaxEstimatedTets = 2e7;

std::mutex& GmshMutex() {
  static std::mutex mutex;
  return mutex;
}

/// One Gmsh API session: holds the Gmsh mutex, initialises Gmsh quietly (no terminal output,
/// no configuration files, one thread for reproducible meshes) and finalises it on exit, also
/// when an exception leaves the scope. Gmsh sets the process locale from the environment and
/// the calling thread's OpenMP team size to one; the session restores both. Neither copyable
/// nor movable.
class GmshSession {
 public:
  GmshSession() : lock_(GmshMutex()) {
    if (const char* locale = std::setlocale(LC_ALL, nullptr)) saved_locale_ = locale;
#ifdef _OPENMP
    saved_threads_ = omp_get_max_threads();
#endif
    gmsh::initialize(0, nullptr, /*readConfigFiles=*/false);
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::option::setNumber("General.Verbosity", 0);
    gmsh::option::setNumber("General.NumThreads", 1);
  }
  ~GmshSession() {
    try {
      gmsh::finalize();
    } catch (...) {  // nothing sensible to do in a destructor
    }
    if (!saved_locale_.empty()) std::setlocale(LC_ALL, saved_locale_.c_str());
#ifdef _OPENMP
    omp_set_num_threads(saved_threads_);
#endif
  }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

 private:
  std::lock_guard<std::mutex> lock_;
  std::string saved_locale_;
  int saved_threads_ = 1;
};

std::string LastGmshError() {
  std::string error;
  try {
    gmsh::logger::getLastError(error);
  } catch (...) {
  }
  return error.empty() ? "no details" : error;
}

/// Position of `x` along a Z-order (Morton) curve through the box [lo, lo + 1/inv_size]:
/// 10 bits per axis, interleaved.
std::uint32_t MortonKey(const Vec3& x, const Vec3& lo, const Vec3& inv_size) {
  const Vec3 q = ((x - lo).cwiseProduct(inv_size) * 1023.0).cwiseMax(0.0).cwiseMin(1023.0);
  std::uint32_t key = 0;
  for (int bit = 9; bit >= 0; --bit)
    for (int axis = 0; axis < 3; ++axis)
      key = (key << 1) | ((static_cast<std::uint32_t>(q[axis]) >> bit) & 1U);
  return key;
}

/// Renumbers nodes and tets along a Z-order curve (nodes by position, tets by centroid; ties
/// by the old index). Gmsh numbers the tets of a meshed volume in no spatial order: in the
/// heart's shell every run of 512 consecutive tets shared nodes with every other run, so the
/// FEM assembly's chunk colouring (models/fem/tet_assembly.h) found one chunk per colour and
/// ran serially, and each element's data was a cache miss. Along the curve, consecutive tets
/// are neighbours in space and memory.
void SortAlongZOrderCurve(Mesh& mesh) {
  const Index n = mesh.num_nodes();
  const Index ne = mesh.num_tets();
  if (n == 0) return;
  const Vec3 lo = mesh.nodes.rowwise().minCoeff();
  const Vec3 inv_size = (mesh.nodes.rowwise().maxCoeff() - lo).cwiseMax(1e-300).cwiseInverse();
  std::vector<std::pair<std::uint32_t, Index>> order(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i)
    order[static_cast<std::size_t>(i)] = {MortonKey(mesh.nodes.col(i), lo, inv_size), i};
  std::sort(order.begin(), order.end());
  std::vector<int> new_index(static_cast<std::size_t>(n));
  Points nodes(3, n);
  for (Index i = 0; i < n; ++i) {
    const Index old = order[static_cast<std::size_t>(i)].second;
    new_index[static_cast<std::size_t>(old)] = static_cast<int>(i);
    nodes.col(i) = mesh.nodes.col(old);
  }
  mesh.nodes = std::move(nodes);
  for (Index e = 0; e < ne; ++e)
    for (int a = 0; a < 4; ++a)
      mesh.tets(a, e) = new_index[static_cast<std::size_t>(mesh.tets(a, e))];
  for (Index k = 0; k < mesh.edge_node_ends.cols(); ++k) {
    const int a = new_index[static_cast<std::size_t>(mesh.edge_node_ends(0, k))];
    const int b = new_index[static_cast<std::size_t>(mesh.edge_node_ends(1, k))];
    mesh.edge_node_ends(0, k) = std::min(a, b);
    mesh.edge_node_ends(1, k) = std::max(a, b);
  }

  order.resize(static_cast<std::size_t>(ne));
  for (Index e = 0; e < ne; ++e) {
    Vec3 centroid = Vec3::Zero();
    for (int a = 0; a < 4; ++a) centroid += mesh.nodes.col(mesh.tets(a, e));
    order[static_cast<std::size_t>(e)] = {MortonKey(0.25 * centroid, lo, inv_size), e};
  }
  std::sort(order.begin(), order.end());
  Tets tets(4, ne);
  for (Index e = 0; e < ne; ++e)
    tets.col(e) = mesh.tets.col(order[static_cast<std::size_t>(e)].second);
  mesh.tets = std::move(tets);
}

/// Reads all nodes and tets of the current Gmsh model into a mesh, with every tet positively
/// oriented, unused nodes dropped and both numbered along a Z-order curve. `order` 2 reads
/// 10-node tets: their corners make the tets, their edges' middle nodes Mesh::edge_nodes.
Mesh ReadGmshTets(int order) {
  std::vector<std::size_t> node_tags;
  std::vector<double> coords, params;
  gmsh::model::mesh::getNodes(node_tags, coords, params, -1, -1, /*includeBoundary=*/false,
                              /*returnParametricCoord=*/false);
  std::size_t max_tag = 0;
  for (std::size_t tag : node_tags) max_tag = std::max(max_tag, tag);
  std::vector<int> index_of_tag(max_tag + 1, -1);
  Mesh mesh;
  mesh.nodes.resize(3, Index(node_tags.size()));
  for (std::size_t i = 0; i < node_tags.size(); ++i) {
    index_of_tag[node_tags[i]] = int(i);
    mesh.nodes.col(Index(i)) = Vec3(coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]);
  }
  auto index = [&](std::size_t tag) {
    GIPSI_CHECK(tag <= max_tag && index_of_tag[tag] >= 0, "Gmsh tet refers to unknown node");
    return index_of_tag[tag];
  };
  const std::size_t per = order == 2 ? 10 : 4;
  std::vector<std::size_t> element_tags, element_nodes;
  gmsh::model::mesh::getElementsByType(order == 2 ? kGmshTet10 : kGmshTet4, element_tags,
                                       element_nodes);
  mesh.tets.resize(4, Index(element_tags.size()));
  std::map<std::uint64_t, int> middle_of_edge;
  for (std::size_t e = 0; e < element_tags.size(); ++e) {
    const std::size_t* nodes = element_nodes.data() + per * e;
    for (std::size_t a = 0; a < 4; ++a) mesh.tets(Index(a), Index(e)) = index(nodes[a]);
    for (std::size_t k = 0; k + 4 < per; ++k) {
      const int a = index(nodes[kGmshSecondOrderEdges[k][0]]);
      const int b = index(nodes[kGmshSecondOrderEdges[k][1]]);
      middle_of_edge.emplace(EdgeKey(a, b), index(nodes[4 + k]));
    }
    const auto t = mesh.tets.col(Index(e));
    if (TetSignedVolume(mesh.nodes.col(t[0]), mesh.nodes.col(t[1]), mesh.nodes.col(t[2]),
                        mesh.nodes.col(t[3])) < 0)
      std::swap(mesh.tets(2, Index(e)), mesh.tets(3, Index(e)));
  }
  mesh.SeparateEdgeNodes(middle_of_edge);
  mesh.RemoveUnusedNodes();
  SortAlongZOrderCurve(mesh);
  return mesh;
}

/// Adds the boundary triangles of `mesh` (outward), grouped by `classify`, which maps the
/// three corners of a boundary triangle to an index into `names` (or -1: not expected), then a
/// dim-3 group `volume_name` of all tets. Throws InputError naming `what` for an unexpected
/// triangle or an empty group.
void AddBoundaryGroups(Mesh& mesh, const std::vector<std::string>& names,
                       const std::function<int(const Vec3&, const Vec3&, const Vec3&)>& classify,
                       const std::string& volume_name, const std::string& what) {
  const BoundarySurface boundary = ExtractTetBoundary(mesh.nodes, mesh.tets);
  std::vector<MeshGroup> groups;
  for (const auto& name : names) groups.push_back(MeshGroup{name, 2, {}});
  mesh.triangles.resize(3, boundary.num_triangles());
  std::vector<std::vector<Index>> by_group(names.size());
  for (Index t = 0; t < boundary.num_triangles(); ++t) {
    Vec3 x[3];
    for (int a = 0; a < 3; ++a)
      x[a] = mesh.nodes.col(boundary.vertex_to_node[std::size_t(boundary.triangles(a, t))]);
    const int g = classify(x[0], x[1], x[2]);
    if (g < 0)
      ThrowInputError("", what,
                      fmt::format("Gmsh produced a boundary triangle off the expected surfaces, "
                                  "near ({:.4g}, {:.4g}, {:.4g})",
                                  x[0].x(), x[0].y(), x[0].z()));
    by_group[std::size_t(g)].push_back(t);
  }
  Index next = 0;
  for (std::size_t g = 0; g < names.size(); ++g) {
    if (by_group[g].empty())
      ThrowInputError("", what, fmt::format("Gmsh produced no '{}' surface", names[g]));
    for (Index t : by_group[g]) {
      for (int a = 0; a < 3; ++a)
        mesh.triangles(a, next) = boundary.vertex_to_node[std::size_t(boundary.triangles(a, t))];
      groups[g].items.push_back(int(next++));
    }
  }
  MeshGroup volume{volume_name, 3, std::vector<int>(std::size_t(mesh.num_tets()))};
  for (std::size_t e = 0; e < volume.items.size(); ++e) volume.items[e] = int(e);
  groups.push_back(std::move(volume));
  mesh.groups = std::move(groups);
}

/// Runs `build` (which creates an OpenCASCADE model, synchronised here unless `occ_kernel` is
/// false and `build` synchronises its own built-in-kernel model) in a Gmsh session,
/// meshes it in 3-D with maximal element size `mesh_size` (and elevates it to second order, the
/// edges' middle nodes on the model's curved surfaces, for `order` 2) and reads the tets back.
/// Gmsh failures become InputError naming `what`.
Mesh MeshWithGmsh(const std::string& what, double mesh_size, const std::function<void()>& build,
                  bool occ_kernel = true, int order = 1) {
  GmshSession session;
  try {
    gmsh::model::add("gipsi_shell");
    build();
    if (occ_kernel) gmsh::model::occ::synchronize();
    gmsh::option::setNumber("Mesh.MeshSizeMax", mesh_size);
    gmsh::option::setNumber("Mesh.MeshSizeMin", 0.0);
    gmsh::model::mesh::generate(3);
    if (order == 2) gmsh::model::mesh::setOrder(2);
    Mesh mesh = ReadGmshTets(order);
    if (mesh.num_tets() == 0) ThrowInputError("", what, "Gmsh produced no tetrahedra");
    return mesh;
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    ThrowInputError("", what, fmt::format("Gmsh failed: {} ({})", e.what(), LastGmshError()));
  } catch (...) {
    ThrowInputError("", what, fmt::format("Gmsh failed: {}", LastGmshError()));
  }
}

void CheckOrder(const std::string& what, int order) {
  if (order != 1 && order != 2)
    ThrowInputError("", what, fmt::format("order must be 1 or 2, got {}", order));
}

void CheckPositive(const std::string& what, const char* name, double value) {
  if (!(value > 0) || !std::isfinite(value))
    ThrowInputError("", what, fmt::format("{} must be a positive number, got {}", name, value));
}

void CheckMeshCount(const std::string& what, double volume, double mesh_size) {
  // A regular tet of edge h has volume h³/(6√2).
  const double estimate = volume / (mesh_size * mesh_size * mesh_size / (6 * std::sqrt(2.0)));
  if (estimate > kMaxEstimatedTets)
    ThrowInputError("", what,
                    fmt::format("mesh_size {} is too small for this shell (about {:.3g} "
                                "tetrahedra, limit {:.3g})",
                                mesh_size, estimate, kMaxEstimatedTets));
}

/// Volume of the ellipsoid (x²+y²)/a² + z²/c² <= 1 below z = zb (−c <= zb <= c):
/// π a² ∫_{−c}^{zb} (1 − z²/c²) dz.
double TruncatedEllipsoidVolume(double a, double c, double zb) {
  return std::numbers::pi * a * a * ((zb + c) - (zb * zb * zb + c * c * c) / (3 * c * c));
}

}  // namespace

Mesh MakeEllipsoidShell(const EllipsoidShellSpec& spec) {
  const std::string what = "ellipsoid shell";
  CheckPositive(what, "endo_short", spec.endo_short);
  CheckPositive(what, "endo_long", spec.endo_long);
  CheckPositive(what, "epi_short", spec.epi_short);
  CheckPositive(what, "epi_long", spec.epi_long);
  CheckPositive(what, "mesh_size", spec.mesh_size);
  if (!(spec.endo_short < spec.epi_short) || !(spec.endo_long < spec.epi_long))
    ThrowInputError("", what,
                    fmt::format("the endocardium ({} x {}) must lie inside the epicardium "
                                "({} x {}): both semi-axes must be smaller",
                                spec.endo_short, spec.endo_long, spec.epi_short, spec.epi_long));
  if (!(std::abs(spec.base_z) < spec.endo_long))
    ThrowInputError("", what,
                    fmt::format("base_z {} must cut both surfaces: expected |base_z| < endo_long "
                                "{}",
                                spec.base_z, spec.endo_long));
  CheckMeshCount(what,
                 TruncatedEllipsoidVolume(spec.epi_short, spec.epi_long, spec.base_z) -
                     TruncatedEllipsoidVolume(spec.endo_short, spec.endo_long, spec.base_z),
                 spec.mesh_size);

  CheckOrder(what, spec.order);
  Mesh mesh = MeshWithGmsh(
      what, spec.mesh_size,
      [&] {
        namespace occ = gmsh::model::occ;
        const int epi = occ::addSphere(0, 0, 0, 1);
        occ::dilate({{3, epi}}, 0, 0, 0, spec.epi_short, spec.epi_short, spec.epi_long);
        const int endo = occ::addSphere(0, 0, 0, 1);
        occ::dilate({{3, endo}}, 0, 0, 0, spec.endo_short, spec.endo_short, spec.endo_long);
        gmsh::vectorpair shell, cut;
        std::vector<gmsh::vectorpair> map;
        occ::cut({{3, epi}}, {{3, endo}}, shell, map);
        const double l = 2 * (spec.epi_short + spec.epi_long);
        const int top = occ::addBox(-l, -l, spec.base_z, 2 * l, 2 * l, l);
        occ::cut(shell, {{3, top}}, cut, map);
      },
      /*occ_kernel=*/true, spec.order);

  // Group boundary triangles: base (all corners on z = base_z), else the closer ellipsoid.
  const double plane_tol = 1e-6 * spec.epi_long;
  auto ellipsoid_gap = [](const Vec3& x, double a, double c) {
    const double f = (x.x() * x.x() + x.y() * x.y()) / (a * a) + x.z() * x.z() / (c * c);
    return std::abs(std::sqrt(f) - 1) * a;
  };
  AddBoundaryGroups(
      mesh, {"endo", "epi", "base"},
      [&](const Vec3& a, const Vec3& b, const Vec3& c) {
        if (std::abs(a.z() - spec.base_z) <= plane_tol &&
            std::abs(b.z() - spec.base_z) <= plane_tol &&
            std::abs(c.z() - spec.base_z) <= plane_tol)
          return 2;
        const Vec3 centroid = (a + b + c) / 3;
        return ellipsoid_gap(centroid, spec.endo_short, spec.endo_long) <
                       ellipsoid_gap(centroid, spec.epi_short, spec.epi_long)
                   ? 0
                   : 1;
      },
      "wall", what);
  return mesh;
}

Mesh MakeCylinderShell(double inner_radius, double outer_radius, double height, double mesh_size,
                       int order) {
  const std::string what = "cylinder shell";
  CheckOrder(what, order);
  CheckPositive(what, "inner_radius", inner_radius);
  CheckPositive(what, "outer_radius", outer_radius);
  CheckPositive(what, "height", height);
  CheckPositive(what, "mesh_size", mesh_size);
  if (!(inner_radius < outer_radius))
    ThrowInputError("", what,
                    fmt::format("inner_radius {} must be smaller than outer_radius {}",
                                inner_radius, outer_radius));
  CheckMeshCount(
      what, std::numbers::pi * (outer_radius * outer_radius - inner_radius * inner_radius) * height,
      mesh_size);

  Mesh mesh = MeshWithGmsh(
      what, mesh_size,
      [&] {
        namespace occ = gmsh::model::occ;
        const int outer = occ::addCylinder(0, 0, 0, 0, 0, height, outer_radius);
        // The hole sticks out at both ends so that the cut has no coincident faces.
        const int inner = occ::addCylinder(0, 0, -height, 0, 0, 3 * height, inner_radius);
        gmsh::vectorpair out;
        std::vector<gmsh::vectorpair> map;
        occ::cut({{3, outer}}, {{3, inner}}, out, map);
      },
      /*occ_kernel=*/true, order);

  const double plane_tol = 1e-6 * std::max(height, outer_radius);
  AddBoundaryGroups(
      mesh, {"inner", "outer", "bottom", "top"},
      [&](const Vec3& a, const Vec3& b, const Vec3& c) {
        for (int g = 0; g < 2; ++g) {
          const double z = g == 0 ? 0.0 : height;
          if (std::abs(a.z() - z) <= plane_tol && std::abs(b.z() - z) <= plane_tol &&
              std::abs(c.z() - z) <= plane_tol)
            return 2 + g;
        }
        const Vec3 centroid = (a + b + c) / 3;
        const double r = centroid.head<2>().norm();
        return std::abs(r - inner_radius) < std::abs(r - outer_radius) ? 0 : 1;
      },
      "wall", what);
  return mesh;
}

Mesh MakeTetsInSurface(const Points& vertices, const Triangles& triangles, double mesh_size) {
  const std::string what = "tetrahedralized surface";
  CheckPositive(what, "size", mesh_size);
  if (triangles.cols() < 4 || vertices.cols() < 4)
    ThrowInputError("", what, "the surface needs at least 4 vertices and 4 triangles");
  for (Index t = 0; t < triangles.cols(); ++t)
    for (int a = 0; a < 3; ++a)
      if (triangles(a, t) < 0 || triangles(a, t) >= vertices.cols())
        ThrowInputError("", what,
                        fmt::format("triangle {} refers to vertex {} (have {})", t, triangles(a, t),
                                    vertices.cols()));
  // Gmsh cannot fill an open or inconsistently oriented surface; say so before calling it.
  try {
    const EnclosedVolume check(triangles, vertices.cols());
    if (check.num_loops() > 0)
      ThrowInputError("", what,
                      fmt::format("the surface is not closed ({} boundary loop(s)); only a "
                                  "closed surface encloses a volume",
                                  check.num_loops()));
  } catch (const InputError& e) {
    std::string message = e.what();
    if (message.rfind(what, 0) == 0) throw;
    ThrowInputError("", what, message);
  }
  // Enclosed volume (divergence theorem) bounds the tet count; its sign tells the orientation.
  double volume = 0;
  for (Index t = 0; t < triangles.cols(); ++t)
    volume += vertices.col(triangles(0, t))
                  .dot(vertices.col(triangles(1, t)).cross(vertices.col(triangles(2, t)))) /
              6.0;
  CheckMeshCount(what, std::abs(volume), mesh_size);

  Mesh mesh = MeshWithGmsh(
      what, mesh_size,
      [&] {
        const int surface = gmsh::model::addDiscreteEntity(2);
        std::vector<std::size_t> node_tags(std::size_t(vertices.cols()));
        std::vector<double> coords(std::size_t(3 * vertices.cols()));
        for (Index v = 0; v < vertices.cols(); ++v) {
          node_tags[std::size_t(v)] = std::size_t(v + 1);
          for (int a = 0; a < 3; ++a) coords[std::size_t(3 * v + a)] = vertices(a, v);
        }
        gmsh::model::mesh::addNodes(2, surface, node_tags, coords);
        std::vector<std::size_t> tri_nodes(std::size_t(3 * triangles.cols()));
        for (Index t = 0; t < triangles.cols(); ++t)
          for (int a = 0; a < 3; ++a)
            tri_nodes[std::size_t(3 * t + a)] = std::size_t(triangles(a, t) + 1);
        gmsh::model::mesh::addElementsByType(surface, /*triangle*/ 2, {}, tri_nodes);
        constexpr double kCrease = 40 * std::numbers::pi / 180;
        gmsh::model::mesh::classifySurfaces(kCrease, /*boundary=*/true,
                                            /*forReparametrization=*/true, std::numbers::pi);
        gmsh::model::mesh::createGeometry();
        gmsh::vectorpair surfaces;
        gmsh::model::getEntities(surfaces, 2);
        std::vector<int> tags;
        for (const auto& [dim, tag] : surfaces) tags.push_back(tag);
        const int loop = gmsh::model::geo::addSurfaceLoop(tags);
        gmsh::model::geo::addVolume({loop});
        gmsh::model::geo::synchronize();
      },
      /*occ_kernel=*/false);
  AddBoundaryGroups(
      mesh, {"surface"}, [](const Vec3&, const Vec3&, const Vec3&) { return 0; }, "volume", what);
  return mesh;
}

}  // namespace gipsi
