#include "gipsi/haptics/local_model.h"

#include <algorithm>

#include "gipsi/base/error.h"

namespace gipsi {

void AnchorLocalState(const LocalDynamicModel& model, LocalState& state) noexcept {
  const Index n = model.dofs();
  state.u.setZero(n);
  state.v = model.initial_velocity.head(n);
}

double StepLocalModel(const LocalDynamicModel& model, const LocalCoupling& coupling, double depth,
                      double depth_rate, LocalState& state) noexcept {
  const double h = model.period;
  LocalVector v_free = model.step_bias;
  v_free.noalias() += model.step_v * state.v;
  v_free.noalias() += model.step_u * state.u;
  const double vn_free = model.push.dot(v_free);
  const double y_free = model.push.dot(state.u) + h * vn_free;
  const double k = coupling.stiffness, b = coupling.damping;
  const double num = k * (depth - y_free) + b * (depth_rate - vn_free);
  const double den = 1 + (k * h + b) * model.compliance;
  const double force = std::max(0.0, num / den);
  state.v = v_free;
  state.v.noalias() += force * model.gain;
  state.u.noalias() += h * state.v;
  return force;
}

double LocalSurfaceDepth(const LocalDynamicModel& model, const LocalState& state) noexcept {
  return model.push.dot(state.u);
}

double LocalEnergy(const LocalDynamicModel& model, const LocalCoupling& coupling,
                   const LocalState& state, double depth) noexcept {
  const double stretch = std::max(0.0, depth - LocalSurfaceDepth(model, state));
  return 0.5 * state.u.dot(model.stiffness * state.u) +
         0.5 * state.v.dot(model.mass.cwiseProduct(state.v)) - model.load.dot(state.u) +
         0.5 * coupling.stiffness * stretch * stretch;
}

}  // namespace gipsi
