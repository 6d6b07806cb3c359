#pragma once
/// @file
/// Regions select nodes and boundary faces, for boundary conditions, loads and probes.

#include <string>
#include <variant>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Every node / face.
struct AllRegion {};
/// Axis-aligned box [min, max] (inclusive, with a tolerance of 1e-9 of the mesh diagonal).
struct BoxRegion {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();
};
/// Points x with (x − point)·n >= −tolerance, n = normal/|normal| (the side the normal points
/// to; the tolerance is 1e-9 of the mesh diagonal). A zero normal is an InputError.
struct HalfSpaceRegion {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
};
/// Ball of given centre and radius (>= 0; inclusive, with a tolerance of 1e-9 of the mesh
/// diagonal).
struct SphereRegion {
  Vec3 center = Vec3::Zero();
  double radius = 0;
};
/// A named group of the mesh (Gmsh physical group, region marker): its nodes (dim 0), or the
/// nodes of its triangles (dim 2) or tets (dim 3).
struct GroupRegion {
  std::string name;
};
/// Explicit domain node ids.
struct NodeIdsRegion {
  std::vector<int> ids;
};

using Region =
    std::variant<AllRegion, BoxRegion, HalfSpaceRegion, SphereRegion, GroupRegion, NodeIdsRegion>;

/// Domain nodes in `region`, sorted and unique. Throws InputError for an unknown group name
/// (listing the available ones), an out-of-range id, a zero half-space normal or a negative
/// sphere radius.
std::vector<int> SelectNodes(const Region& region, const Mesh& mesh);
/// As above, the geometric tests (box, half-space, sphere) at the absolute `tolerance` instead of
/// 1e-9 of `mesh`'s own diagonal: for one rank's part of a mesh, the whole mesh's
/// RegionTolerance, so every part selects what the whole mesh would.
std::vector<int> SelectNodes(const Region& region, const Mesh& mesh, double tolerance);
/// The geometric regions' tolerance for a mesh whose bounding box is [low, high]: 1e-9 of its
/// diagonal.
double RegionTolerance(const Vec3& low, const Vec3& high);

/// Boundary vertices (indices into `boundary.vertex_to_node`) whose domain node is in `region`.
std::vector<int> SelectBoundaryVertices(const Region& region, const Mesh& mesh,
                                        const BoundarySurface& boundary);

/// Boundary triangles in `region`: for a group of triangles, the boundary triangles with the
/// same three nodes; otherwise those whose three vertices are all selected.
std::vector<int> SelectBoundaryFaces(const Region& region, const Mesh& mesh,
                                     const BoundarySurface& boundary);

}  // namespace gipsi
GIPSI_EXPORT_END
