#pragma once
/// @file
/// `FemState`: what a FemSolid carries from one step to the next, as a state value type
/// (gipsi/base/state_value.h). Everything else in a FemSolid is its model (mesh, material,
/// parameters, assembled patterns), a cache derived from this state (positions, the Newton
/// matrix and its kept factorisation, the damping matrix of the step) or work of the step in
/// progress.

#include <cstdint>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/base/state_value.h"
#include "gipsi/numerics/implicit_scheme.h"
#include "gipsi/numerics/newton.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A coupled or pressure-driven cavity's state. Copyable.
struct FemCavityState {
  double pressure = 0;   ///< [Pa]: written through the field, or solved when coupled
  double stiffness = 0;  ///< −∂p/∂V of the coupled law at `pressure` [Pa/m³]

  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("pressure", s.pressure);
    v("stiffness", s.stiffness);
  }
};

/// Copyable. Shapes: N nodes, E elements, F boundary faces.
struct FemState {
  static constexpr const char* kTag = "FemState";
  static constexpr std::uint32_t kVersion = 1;

  ImplicitScheme scheme;  ///< displacements u, velocities, accelerations and their history (3N)
  /// The previous step's loads (s = 0 of the load interpolation within a step).
  VecX f_nodal_prev;     ///< 3N: gravity + nodal forces + external_force
  VecX pressure_prev;    ///< per boundary face [Pa]
  Points traction_prev;  ///< 3 by F [Pa]
  bool have_prev_loads = false;
  /// Fields written from outside.
  Stamped<Points> external_force;  ///< 3 by N [N]
  VecX active_tension;             ///< per element [Pa]
  VecX nodal_active_tension;       ///< per node [Pa], used when active_from_nodes
  bool active_from_nodes = false;
  /// Per element material axes, empty if the law needs none and no fibres were written.
  Stamped<std::vector<Mat3>> axes;
  std::vector<FemCavityState> cavities;
  /// Largest absolute row sum of the last Jacobian: sets the round-off floor of the next
  /// step's first residual.
  double jacobian_norm = 0;
  NewtonStats last_newton;  ///< of the last solve (failure messages and the profile read it)

  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("scheme", s.scheme);
    v("f_nodal_prev", s.f_nodal_prev, Shape::kFixed);
    v("pressure_prev", s.pressure_prev, Shape::kFixed);
    v("traction_prev", s.traction_prev, Shape::kFixed);
    v("have_prev_loads", s.have_prev_loads);
    v("external_force", s.external_force, Shape::kFixed);
    v("active_tension", s.active_tension, Shape::kFixed);
    v("nodal_active_tension", s.nodal_active_tension, Shape::kFixed);
    v("active_from_nodes", s.active_from_nodes);
    v("axes", s.axes);  // set on the first fibre write when the law needs none
    v("cavities", s.cavities, Shape::kFixed);
    v("jacobian_norm", s.jacobian_norm);
    v("last_newton", s.last_newton);
  }
};

}  // namespace gipsi
GIPSI_EXPORT_END
