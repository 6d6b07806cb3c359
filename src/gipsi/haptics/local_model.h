#pragma once
/// @file
/// The haptic side of local dynamic models (gipsi/core/local_model.h, where the model and its
/// equations are described): the virtual coupling between the device and the contact node, the
/// local state, and the allocation-free step a haptic tick runs against a published model.

#include "gipsi/base/export.h"
#include "gipsi/core/local_model.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The virtual coupling between the device and the contact node. Plain struct.
struct LocalCoupling {
  double stiffness = 5000;  ///< k_c [N/m]
  double damping = 0;       ///< b_c [N·s/m]
};

/// Local state of a model on the haptic side. Plain struct; never allocates.
struct LocalState {
  LocalVector u;  ///< displacements from the anchor [m]
  LocalVector v;  ///< velocities [m/s]
};

/// Resets `state` to the model's anchor (u = 0, v = the anchor velocities).
void AnchorLocalState(const LocalDynamicModel& model, LocalState& state) noexcept;

/// Advances `state` by one period h for a device at `depth` d [m] below the tangent plane,
/// moving inward at `depth_rate` [m/s]; returns the normal contact force F ≥ 0 [N].
/// Allocation-free, noexcept.
double StepLocalModel(const LocalDynamicModel& model, const LocalCoupling& coupling, double depth,
                      double depth_rate, LocalState& state) noexcept;

/// Depth of the contact node below the anchor plane, y = Pᵀ u [m] (the proxy's depth).
[[nodiscard]] double LocalSurfaceDepth(const LocalDynamicModel& model,
                                       const LocalState& state) noexcept;

/// Energy stored in the local model relative to the anchor, ½ uᵀ K u + ½ vᵀ M v − qᵀ u, plus
/// the coupling spring's ½ k_c max(0, d − y)² [J].
[[nodiscard]] double LocalEnergy(const LocalDynamicModel& model, const LocalCoupling& coupling,
                                 const LocalState& state, double depth) noexcept;

}  // namespace gipsi
GIPSI_EXPORT_END
