#pragma once
/// @file
/// Mesh generators: structured tet boxes/beams, triangle sheets, and shells (the simplified left
/// ventricle) through the Gmsh C++ API.

#include <array>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// How each hexahedral cell of a structured box is cut into tetrahedra.
/// The most elements a generator makes (a box of 20 million tets needs about 3 GB to build and
/// assemble): larger requests are refused with an InputError rather than exhausting memory.
inline constexpr double kMaxGeneratedElements = 2e7;

enum class HexSplit {
  kSix,   ///< 6 tets around the main diagonal (Kuhn/Freudenthal)
  kFive,  ///< 5 tets (a central tet and four corners), alternating by cell parity to conform
};

/// A box [min, max] split into cells[0]×cells[1]×cells[2] hexahedra, each cut into 6 (or 5)
/// positively oriented tets that conform across cells. Node (i,j,k) has index
/// i + (nx+1)(j + (ny+1)k). Boundary triangles are included, with groups "xmin", "xmax", "ymin",
/// "ymax", "zmin", "zmax" (dim 2) and "volume" (dim 3). Throws InputError unless max > min and
/// cells >= 1.
Mesh MakeTetBox(const Vec3& min, const Vec3& max, const std::array<int, 3>& cells,
                HexSplit split = HexSplit::kSix);

/// A flat sheet of triangles spanned by `origin + s·edge_u + t·edge_v`, s,t in [0,1], with
/// cells[0]×cells[1] quads each cut into 2 triangles. Node (i,j) has index i + (nu+1)·j. Groups
/// (dim 0, nodes): "u0", "u1", "v0", "v1" for the four edges. Throws InputError for cells < 1
/// or parallel edges.
Mesh MakeTriangleSheet(const Vec3& origin, const Vec3& edge_u, const Vec3& edge_v,
                       const std::array<int, 2>& cells);

/// Parameters of a truncated ellipsoidal shell (a simplified left ventricle): inner (endo) and
/// outer (epi) semi-axes; x and y share the short radius, z the long one; the shell is cut at
/// z = base_z and keeps z <= base_z.
struct EllipsoidShellSpec {
  double endo_short = 7, endo_long = 17;
  double epi_short = 10, epi_long = 20;
  double base_z = 5;
  double mesh_size = 2;
  /// 2: second-order tets from Gmsh, their edges' middle nodes on the ellipsoids
  /// (Mesh::edge_nodes; curved MixedSolid elements). Objects on linear tets see the same
  /// corners either way.
  int order = 1;
};
/// Tet mesh of the shell by Gmsh (OpenCASCADE kernel; `mesh_size` is the largest element size;
/// `order` 1 or 2).
/// Tets are positively oriented; the boundary triangles are the closed boundary of the tets,
/// oriented out of the wall (on "endo" they point into the cavity). Groups: "endo", "epi",
/// "base" (dim 2) and "wall" (dim 3). Throws InputError for inconsistent dimensions (endo must
/// lie inside epi, base_z must cut both), a mesh size giving over 2e7 tets, or if Gmsh fails.
/// Thread-safe: Gmsh's global state is guarded by a process-wide mutex.
Mesh MakeEllipsoidShell(const EllipsoidShellSpec& spec);

/// A hollow cylinder around the z axis from z=0 to z=height, meshed like `MakeEllipsoidShell`
/// (`order` 2: second order, the middle nodes on the cylinders).
/// Groups: "inner", "outer", "bottom", "top" (dim 2), "wall" (dim 3). Throws InputError for
/// inner >= outer, a non-positive size, too many tets, or if Gmsh fails.
Mesh MakeCylinderShell(double inner_radius, double outer_radius, double height, double mesh_size,
                       int order = 1);

/// Tetrahedralises the volume enclosed by a closed triangle surface (`vertices` 3 by V,
/// `triangles` 3 by T) with Gmsh: the surface is reparametrised (Gmsh's classifySurfaces and
/// createGeometry, splitting it at creases sharper than 40°) and remeshed at `mesh_size`, then
/// the volume is meshed with tets no larger than `mesh_size`. Groups: "surface" (dim 2) and
/// "volume" (dim 3). Throws InputError if the surface is not a closed manifold Gmsh can mesh,
/// or for a mesh size giving over 2e7 tets. Thread-safe (the Gmsh mutex).
Mesh MakeTetsInSurface(const Points& vertices, const Triangles& triangles, double mesh_size);

}  // namespace gipsi
GIPSI_EXPORT_END
