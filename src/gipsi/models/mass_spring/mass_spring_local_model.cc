#include "gipsi/models/mass_spring/mass_spring_local_model.h"

#include "gipsi/base/error.h"
#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {

MassSpringNeighbourhood::MassSpringNeighbourhood(MassSpring& object, int rings)
    : object_(object), rings_(rings) {
  GIPSI_CHECK(rings >= 0, "negative ring count {}", rings);
  const Index n = object.num_nodes();
  node_springs_.resize(static_cast<std::size_t>(n));
  for (Index s = 0; s < object.num_springs(); ++s)
    for (int e = 0; e < 2; ++e)
      node_springs_[static_cast<std::size_t>(object.springs()(e, s))].push_back(
          static_cast<int>(s));
  local_index_.assign(static_cast<std::size_t>(n), -1);
}

SimObject& MassSpringNeighbourhood::object() { return object_; }

bool MassSpringNeighbourhood::Build(Index vertex, const Vec3& normal, double anchor_force,
                                    double period, LocalDynamicModel& out) {
  out.active = false;
  const MassSpring& ms = object_;
  const std::vector<std::uint8_t> fixed = ConstrainedNodes(ms);
  const int contact = ms.boundary().vertex_to_node[static_cast<std::size_t>(vertex)];
  if (fixed[static_cast<std::size_t>(contact)]) return false;
  // Breadth-first over springs: rings 0..rings_ move (free nodes only), up to the cap.
  for (int i : local_) local_index_[static_cast<std::size_t>(i)] = -1;
  local_.clear();
  local_.push_back(contact);
  local_index_[static_cast<std::size_t>(contact)] = 0;
  std::size_t ring_begin = 0;
  for (int ring = 1; ring <= rings_; ++ring) {
    const std::size_t ring_end = local_.size();
    for (std::size_t i = ring_begin; i < ring_end; ++i) {
      for (int s : node_springs_[static_cast<std::size_t>(local_[i])]) {
        for (int e = 0; e < 2; ++e) {
          const int other = ms.springs()(e, s);
          if (local_index_[static_cast<std::size_t>(other)] >= 0 ||
              fixed[static_cast<std::size_t>(other)] ||
              static_cast<int>(local_.size()) >= kMaxLocalNodes)
            continue;
          local_index_[static_cast<std::size_t>(other)] = static_cast<int>(local_.size());
          local_.push_back(other);
        }
      }
    }
    ring_begin = ring_end;
  }
  const Index m = static_cast<Index>(local_.size());
  const Index n = ms.num_nodes();
  const VecX& x = ms.state().x;
  const MassSpringParams& params = ms.params();
  const HookeSpring hooke;
  const SpringLaw& law = params.law ? *params.law : static_cast<const SpringLaw&>(hooke);
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(3 * m, 3 * m), c = Eigen::MatrixXd::Zero(3 * m, 3 * m);
  VecX mass(3 * m), v0(3 * m), a0(3 * m);
  xdot_.resize(ms.ode_size());
  ms.CalcDerivative(ms.time(), x, xdot_);
  for (Index i = 0; i < m; ++i) {
    const Index node = local_[static_cast<std::size_t>(i)];
    mass.segment<3>(3 * i).setConstant(ms.masses()[node]);
    v0.segment<3>(3 * i) = x.segment<3>(3 * n + 3 * node);
    a0.segment<3>(3 * i) = xdot_.segment<3>(3 * n + 3 * node);
    c.block<3, 3>(3 * i, 3 * i) += params.drag * ms.masses()[node] * Mat3::Identity();
  }
  // Springs with at least one moving end; a fixed end contributes to the diagonal only.
  for (Index i = 0; i < m; ++i) {
    for (int s : node_springs_[static_cast<std::size_t>(local_[static_cast<std::size_t>(i)])]) {
      const int a = ms.springs()(0, s), b = ms.springs()(1, s);
      const int la = local_index_[static_cast<std::size_t>(a)];
      const int lb = local_index_[static_cast<std::size_t>(b)];
      if (la >= 0 && lb >= 0 && (la < i || lb < i)) continue;  // assembled from the other end
      const Vec3 d = x.segment<3>(3 * b) - x.segment<3>(3 * a);
      const double length = d.norm();
      const Vec3 dir = d / length;
      const double rest = ms.rest_lengths()[s];
      const double tension = law.Tension(length, rest, params.stiffness);
      const double tangent = law.TangentStiffness(length, rest, params.stiffness);
      const Mat3 nn = dir * dir.transpose();
      const Mat3 ks = tangent * nn + (tension / length) * (Mat3::Identity() - nn);
      const Mat3 cs = params.damping * nn;
      for (int ea = 0; ea < 2; ++ea) {
        const int li = ea == 0 ? la : lb;
        if (li < 0) continue;
        k.block<3, 3>(3 * li, 3 * li) += ks;
        c.block<3, 3>(3 * li, 3 * li) += cs;
        const int lj = ea == 0 ? lb : la;
        if (lj < 0) continue;
        k.block<3, 3>(3 * li, 3 * lj) -= ks;
        c.block<3, 3>(3 * li, 3 * lj) -= cs;
      }
    }
  }
  if (!DiscretiseLocalModel(mass, c, k, v0, a0, anchor_force, x.segment<3>(3 * contact), normal,
                            period, out))
    return false;
  out.contact_vertex = static_cast<int>(vertex);
  return true;
}

}  // namespace gipsi
