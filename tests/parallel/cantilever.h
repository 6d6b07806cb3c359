#pragma once
// The soft cantilever the MPI tests split (scenes/cantilever.json): 10 × 1 × 1 cm of 480 tets,
// corotational, E 100 kPa, ν 0.45, consistent mass, Rayleigh α 2 /s, backward Euler, Newton and
// CG to 1e-11 (tight, so that two runs are both near each step's exact solution), clamped at
// x = 0. Released under gravity it sags 7 cm.

#include <memory>
#include <string>

#include "gipsi/core/sim_object.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/solid_laws.h"

namespace gipsi::test {

inline FemParams CantileverParams(const std::string& preconditioner = "") {
  FemParams p;
  p.material = std::make_shared<CorotationalSolid>(1e5, 0.45);
  p.rayleigh_mass = 2.0;
  p.scheme = ImplicitSchemeKind::kBackwardEuler;
  p.newton.tolerance = 1e-11;
  p.linear_solver.tolerance = 1e-11;
  if (!preconditioner.empty()) p.linear_solver.preconditioner = preconditioner;
  return p;
}

inline std::shared_ptr<const Mesh> CantileverMesh() {
  return std::make_shared<Mesh>(MakeTetBox(Vec3::Zero(), Vec3(0.1, 0.01, 0.01), {20, 2, 2}));
}

// Holds the vertices at x = 0 of `object`'s boundary (for a view with the whole mesh, the whole
// mesh's; for a part's FemSolid, its part's).
inline void Clamp(SimObject& object) {
  const BoundarySurface& b = object.boundary();
  for (Index v = 0; v < b.num_vertices(); ++v)
    if (object.domain().nodes(0, b.vertex_to_node[static_cast<std::size_t>(v)]) == 0)
      object.boundary_conditions().Fix(v);
}

}  // namespace gipsi::test
