#pragma once
/// @file
/// `MixedState`: what a MixedSolid carries from one step to the next, as a state value type
/// (gipsi/base/state_value.h). Everything else in a MixedSolid is its model (the P2 mesh,
/// material, parameters, the Jacobian's pattern), a cache derived from this state (vertex
/// positions; the Newton solver's warm start and kept factorisation) or work of the step in
/// progress (this step's loads and constraint targets, gathered afresh every step).

#include <cstdint>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/base/state_value.h"
#include "gipsi/numerics/implicit_scheme.h"
#include "gipsi/numerics/newton.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Copyable. Shapes: N P2 nodes, V vertices, E elements, F boundary faces.
struct MixedState {
  static constexpr const char* kTag = "MixedState";
  static constexpr std::uint32_t kVersion = 3;

  VecX z;  ///< the unknowns: displacements (3N, node-major), then scaled pressures (V)
  /// The previous step's loads (s = 0 of the load ramp within a step).
  VecX force_prev;       ///< 3V nodal forces [N]
  VecX pressure_prev;    ///< per boundary face [Pa]
  Points traction_prev;  ///< 3 by F [Pa]
  VecX active_prev;      ///< per element active tension [Pa]
  bool have_prev = false;
  /// Fields written from outside.
  Stamped<Points> external_force;  ///< 3 by V [N]
  VecX active_new;                 ///< per element active tension [Pa]
  /// Material axes (fibre, sheet, normal) at each quadrature point, 4 per element.
  Stamped<std::vector<Mat3>> axes;
  /// The time scheme's history over the displacement unknowns (3N; static: kind only).
  ImplicitScheme scheme;
  VecX cavity_pressure;     ///< per cavity [Pa]
  NewtonStats last_newton;  ///< of the last increment (the field "newton_iterations")
  std::int64_t total_iterations = 0;

  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("z", s.z, Shape::kFixed);
    v("force_prev", s.force_prev, Shape::kFixed);
    v("pressure_prev", s.pressure_prev, Shape::kFixed);
    v("traction_prev", s.traction_prev, Shape::kFixed);
    v("active_prev", s.active_prev, Shape::kFixed);
    v("have_prev", s.have_prev);
    v("external_force", s.external_force, Shape::kFixed);
    v("active_new", s.active_new, Shape::kFixed);
    v("axes", s.axes, Shape::kFixed);
    v("scheme", s.scheme);
    v("cavity_pressure", s.cavity_pressure, Shape::kFixed);
    v("last_newton", s.last_newton);
    v("total_iterations", s.total_iterations);
  }
};

}  // namespace gipsi
GIPSI_EXPORT_END
