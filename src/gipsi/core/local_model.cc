#include "gipsi/core/local_model.h"

#include <algorithm>

#include "gipsi/base/error.h"
#include "gipsi/core/sim_object.h"

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

std::vector<std::uint8_t> ConstrainedNodes(const SimObject& object) {
  std::vector<std::uint8_t> fixed(static_cast<std::size_t>(object.domain().num_nodes()), 0);
  const BoundarySurface& bnd = object.boundary();
  const BoundaryConditions& bcs = object.boundary_conditions();
  for (Index j = 0; j < bnd.num_vertices(); ++j)
    for (int a = 0; a < 3; ++a)
      if (bcs.kind(j, a) != ConstraintKind::kFree)
        fixed[static_cast<std::size_t>(bnd.vertex_to_node[static_cast<std::size_t>(j)])] = 1;
  return fixed;
}

}  // namespace gipsi
