#include "gipsi/haptics/local_model.h"

#include <algorithm>

#include "gipsi/base/error.h"

namespace gipsi {

bool DiscretiseLocalModel(const VecX& mass, const Eigen::MatrixXd& damping,
                          const Eigen::MatrixXd& stiffness, const VecX& v0, const VecX& a0,
                          double anchor_force, const Vec3& point, const Vec3& normal, double period,
                          LocalDynamicModel& out) {
  const Index n = mass.size();
  GIPSI_CHECK(n % 3 == 0 && n >= 3 && n <= kMaxLocalDofs, "local model with {} dofs", n);
  GIPSI_CHECK(damping.rows() == n && damping.cols() == n && stiffness.rows() == n &&
                  stiffness.cols() == n && v0.size() == n && a0.size() == n,
              "local model matrices of inconsistent sizes");
  GIPSI_CHECK(period > 0, "haptic period {} s", period);
  out.active = false;
  const double h = period;
  const VecX p = [&] {
    VecX v = VecX::Zero(n);
    v.head<3>() = -normal.normalized();
    return v;
  }();
  const Eigen::MatrixXd m_over_h = (mass / h).asDiagonal();
  const Eigen::MatrixXd s = m_over_h + damping + h * stiffness;
  const VecX q = mass.cwiseProduct(a0) + damping * v0 - anchor_force * p;
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(s);
  if (!(std::abs(lu.determinant()) > 0)) return false;
  const Eigen::MatrixXd step_v = lu.solve(m_over_h);
  const Eigen::MatrixXd step_u = -lu.solve(stiffness);
  const VecX bias = lu.solve(q);
  const VecX gain = lu.solve(p);
  if (!step_v.allFinite() || !step_u.allFinite() || !bias.allFinite() || !gain.allFinite())
    return false;
  out.period = h;
  out.point = point;
  out.normal = normal.normalized();
  out.anchor_force = anchor_force;
  out.num_nodes = static_cast<int>(n / 3);
  out.step_v = step_v;
  out.step_u = step_u;
  out.step_bias = bias;
  out.gain = gain;
  out.push = p;
  out.compliance = p.dot(gain);
  out.initial_velocity = v0;
  out.stiffness = stiffness;
  out.mass = mass;
  out.load = q;
  out.active = out.compliance > 0;
  return out.active;
}

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
