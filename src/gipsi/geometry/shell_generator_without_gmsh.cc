// The Gmsh-based generators of generators.h in a build without Gmsh (GIPSI_WITH_GMSH=OFF;
// src/CMakeLists.txt compiles this file instead of shell_generator.cc): each refuses with a
// message that says how to get it. The scene loader adds the JSON path of the mesh.

#include "gipsi/base/build_info.h"
#include "gipsi/base/error.h"
#include "gipsi/geometry/generators.h"

namespace gipsi {

Mesh MakeEllipsoidShell(const EllipsoidShellSpec& /*spec*/) {
  throw InputError(MissingFeature("generating an ellipsoid shell", "Gmsh", "GIPSI_WITH_GMSH"));
}

Mesh MakeCylinderShell(double /*inner_radius*/, double /*outer_radius*/, double /*height*/,
                       double /*mesh_size*/, int /*order*/) {
  throw InputError(MissingFeature("generating a cylinder shell", "Gmsh", "GIPSI_WITH_GMSH"));
}

Mesh MakeTetsInSurface(const Points& /*vertices*/, const Triangles& /*triangles*/,
                       double /*mesh_size*/) {
  throw InputError(MissingFeature("filling a surface with tets", "Gmsh", "GIPSI_WITH_GMSH"));
}

}  // namespace gipsi
