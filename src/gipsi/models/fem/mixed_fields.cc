// MixedSolid's fields: what reads and writes them (the node fields on the vertices, the edge
// nodes for quadratic VTU output, the cavities', the reaction with its inertia).

#include "gipsi/models/fem/mixed_solid.h"

namespace gipsi {

bool MixedSolid::GetQuadraticOutput(QuadraticOutput& out) const {
  const Index nv = mesh_.num_vertices;
  const Index ne = mesh_.edges.cols();
  out.edge_positions =
      mesh_.rest.rightCols(ne) + Eigen::Map<const Points>(state_.z.data() + 3 * nv, 3, ne);
  out.edge_ends = mesh_.edges;
  out.tets = mesh_.elements;  // the vertices keep the domain's numbers, edge node k is nv + k
  return true;
}

bool MixedSolid::ReadEdgeNodeField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  const Index nv = mesh_.num_vertices;
  const Index ne = mesh_.edges.cols();
  const auto u = Eigen::Map<const Points>(state_.z.data() + 3 * nv, 3, ne);
  if (id == mech_.displacement) {
    out = u;
  } else if (id == mech_.position) {
    out = mesh_.rest.rightCols(ne) + u;
  } else if (id == mech_.external_force || id == mech_.reaction_force) {
    out.setZero();  // nodal forces live on the vertices (the reaction's edge shares included)
  } else {
    return false;
  }
  return true;
}

void MixedSolid::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  const Index nv = mesh_.num_vertices;
  const Index nu = 3 * mesh_.num_nodes();
  static const VecX kNoVelocity;
  if (!dynamic() && (id == mech_.boundary_velocity || id == mech_.velocity)) {
    out.setZero();  // quasi-static
    return;
  }
  // The scheme's velocities are node-major over the P2 nodes, vertices first.
  const double* velocity = dynamic() ? state_.scheme.v().data() : kNoVelocity.data();
  if (ReadBoundaryKinematics(mech_, id, vertex_positions_, velocity, out)) return;
  if (id == mech_.velocity) {
    out = Eigen::Map<const Points>(velocity, 3, nv);
    return;
  }
  if (id == mech_.position) {
    out = vertex_positions_;
  } else if (id == mech_.displacement) {
    out = vertex_positions_ - domain().nodes;
  } else if (id == mech_.external_force) {
    out = state_.external_force.get();
  } else if (id == mech_.reaction_force) {
    // f_int − f_ext (+ M (a + α v) when dynamic) on the held axes of the vertices, at the
    // current state and loads.
    out.setZero();
    VecX r;
    if (!EvaluateUnconstrained(state_.z, 1.0, r, nullptr)) return;
    if (dynamic()) {
      // M (a + α v) of the last step: the held nodes also carry their neighbours' inertia
      // through the consistent mass.
      const Index nn = mesh_.num_nodes();
      const Points w = Eigen::Map<const Points>(state_.scheme.a().data(), 3, nn) +
                       params_.rayleigh_mass * NodeVelocities();
      r.head(nu) += Eigen::Map<const VecX>(ApplyMass(w).data(), nu);
    }
    // An edge node is held where both its vertices are; its reaction goes half to each, so
    // the vertices carry the whole: for a uniform traction on a 6-node face the vertex nodes'
    // own share is zero (∫ N_vertex dA = 0) and the edge nodes' is all of it.
    const Index nv = mesh_.num_vertices;
    for (Index k = 0; k < mesh_.edges.cols(); ++k)
      for (int a = 0; a < 3; ++a) {
        const Index dof = 3 * (nv + k) + a;
        if (constrained_[static_cast<std::size_t>(dof)] == 0) continue;
        r[3 * mesh_.edges(0, k) + a] += 0.5 * r[dof];
        r[3 * mesh_.edges(1, k) + a] += 0.5 * r[dof];
      }
    const BoundaryConditions& bcs = boundary_conditions();
    const auto& v2n = boundary().vertex_to_node;
    for (std::size_t j = 0; j < v2n.size(); ++j)
      for (int a = 0; a < 3; ++a)
        if (bcs.kind(static_cast<Index>(j), a) != ConstraintKind::kFree)
          out(a, static_cast<Index>(j)) = r[3 * v2n[j] + a];
  } else if (id == f_pressure_) {
    out = pressure_scale_ * state_.z.segment(nu, nv).transpose();
  } else if (id == f_jacobian_) {
    for (Index e = 0; e < mesh_.num_elements(); ++e) {
      double mean = 0;
      for (int q = 0; q < kQuad; ++q) {
        const Mat3 F = DeformationGradient(e, q, state_.z);
        mean += F.determinant() / kQuad;
      }
      out(0, e) = mean;
    }
  } else if (id == f_fibre_) {
    for (Index e = 0; e < mesh_.num_elements(); ++e) out.col(e) = axes_at(e, 0).col(0);
  } else if (id == f_active_) {
    out = state_.active_new.transpose();
  } else if (id == f_volume_) {
    out(0, 0) = CurrentVolume();
  } else if (id == f_energy_) {
    double w = 0;
    for (Index e = 0; e < mesh_.num_elements(); ++e) w += ElementEnergy(e, state_.z);
    out(0, 0) = w;
  } else if (id == f_newton_) {
    out(0, 0) = state_.last_newton.iterations;
  } else if (id == f_kinetic_) {
    out(0, 0) = 0;
    if (dynamic()) {
      const Points v = NodeVelocities();
      out(0, 0) = 0.5 * (v.array() * ApplyMass(v).array()).sum();
    }
  } else {
    for (std::size_t c = 0; c < cavities_.size(); ++c) {
      if (id == cavities_[c].wall.f_volume) out(0, 0) = CavityVolume(c);
      if (id == cavities_[c].wall.f_pressure) out(0, 0) = CavityPressure(c);
    }
  }
}

void MixedSolid::DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) {
  if (id == mech_.external_force) {
    state_.external_force.Write() = in;
  } else if (id == f_fibre_) {
    for (Index e = 0; e < mesh_.num_elements(); ++e) {
      const Vec3 fibre = in.col(e);
      if (fibre.squaredNorm() > 0)
        for (int q = 0; q < kQuad; ++q) SetFibreAt(e, q, fibre);
    }
  } else if (id == f_active_) {
    state_.active_new = in.row(0).transpose();
  } else if (id == mech_.position) {
    // Vertices where written, edge nodes at the mean of their ends (straight edges).
    const Index nv = mesh_.num_vertices;
    const Points u = in - domain().nodes;
    for (Index v = 0; v < nv; ++v) state_.z.segment<3>(3 * v) = u.col(v);
    for (Index k = 0; k < mesh_.edges.cols(); ++k)
      state_.z.segment<3>(3 * (nv + k)) =
          0.5 * (u.col(mesh_.edges(0, k)) + u.col(mesh_.edges(1, k)));
    if (dynamic()) state_.scheme.SetPositions(state_.z.head(3 * mesh_.num_nodes()));
    UpdatePositions();
  } else if (id == mech_.velocity && dynamic()) {
    // Vertices as written, edge nodes at the mean of their ends (exact for a rigid motion on
    // straight edges); the multistep history restarts.
    const Index nv = mesh_.num_vertices;
    VecX v(3 * mesh_.num_nodes());
    for (Index a = 0; a < nv; ++a) v.segment<3>(3 * a) = in.col(a);
    for (Index k = 0; k < mesh_.edges.cols(); ++k)
      v.segment<3>(3 * (nv + k)) = 0.5 * (in.col(mesh_.edges(0, k)) + in.col(mesh_.edges(1, k)));
    state_.scheme.SetVelocity(v);
  }
  for (std::size_t c = 0; c < cavities_.size(); ++c)
    if (id == cavities_[c].wall.f_pressure && cavities_[c].wall.law == nullptr)
      state_.cavity_pressure[static_cast<Index>(c)] = in(0, 0);
  // Velocity writes to a quasi-static object are ignored, and so are pressure writes to a
  // cavity coupled to blood (its pressure is solved with the wall).
}

}  // namespace gipsi
