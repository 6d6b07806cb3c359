#include "gipsi/models/fem/fem_local_model.h"

#include "gipsi/models/fem/fem_solid.h"

namespace gipsi {

FemCondensation::FemCondensation(FemSolid& object) : object_(object) {
  const Mesh& mesh = object.domain();
  lumped_mass_ = VecX::Zero(mesh.num_nodes());
  const double rho = object.params().density;
  for (Index e = 0; e < mesh.num_tets(); ++e)
    for (int a = 0; a < 4; ++a)
      lumped_mass_[mesh.tets(a, e)] += 0.25 * rho * object.assembly().volume(e);
  k_ = object.assembly().MakePattern();
  LinearSolverOptions options;
  options.type = "cholmod";
  options.tolerance = 1e-8;
  solver_ = MakeLinearSolver(options);
}

SimObject& FemCondensation::object() { return object_; }

bool FemCondensation::Build(Index vertex, const Vec3& normal, double anchor_force, double period,
                            LocalDynamicModel& out) {
  out.active = false;
  const FemSolid& fem = object_;
  const std::vector<std::uint8_t> fixed_nodes = ConstrainedNodes(fem);
  const int contact = fem.boundary().vertex_to_node[static_cast<std::size_t>(vertex)];
  if (fixed_nodes[static_cast<std::size_t>(contact)]) return false;
  if (!fem.CalcStiffness(fem.x(), k_)) return false;
  // Eliminate constrained dofs: zero their rows and columns, unit diagonal (the pattern stays,
  // so the symbolic analysis is reused while the constrained set does not change).
  const Index ndof = k_.rows();
  fixed_.assign(static_cast<std::size_t>(ndof), 0);
  for (Index i = 0; i < ndof; ++i) fixed_[static_cast<std::size_t>(i)] = fixed_nodes[i / 3];
  for (Index col = 0; col < k_.outerSize(); ++col) {
    for (SparseMatrix::InnerIterator it(k_, col); it; ++it) {
      if (fixed_[static_cast<std::size_t>(it.row())] || fixed_[static_cast<std::size_t>(col)])
        it.valueRef() = it.row() == col ? 1.0 : 0.0;
    }
  }
  if (!analysed_ || fixed_ != analysed_fixed_) {
    solver_->AnalyzePattern(k_);
    analysed_fixed_ = fixed_;
    analysed_ = true;
  }
  ++factorisations_;
  if (!solver_->Factorize(k_)) return false;
  Mat3 compliance;
  rhs_.setZero(ndof);
  for (int a = 0; a < 3; ++a) {
    rhs_[3 * contact + a] = 1;
    if (!solver_->Solve(rhs_, solution_).converged) return false;
    compliance.col(a) = solution_.segment<3>(3 * contact);
    rhs_[3 * contact + a] = 0;
  }
  compliance = 0.5 * (compliance + compliance.transpose()).eval();
  const Eigen::LDLT<Mat3> small(compliance);
  if (small.info() != Eigen::Success || !(small.vectorD().minCoeff() > 0)) return false;
  condensed_ = small.solve(Mat3::Identity());
  condensed_ = 0.5 * (condensed_ + condensed_.transpose()).eval();
  const double m = lumped_mass_[contact];
  const FemParams& params = fem.params();
  const VecX mass = VecX::Constant(3, m);
  const Eigen::MatrixXd c =
      params.rayleigh_mass * m * Mat3::Identity() + params.rayleigh_stiffness * condensed_;
  const Eigen::MatrixXd k = condensed_;
  const bool dynamic = params.scheme != ImplicitSchemeKind::kStatic;
  const VecX v0 = dynamic ? VecX(fem.v().segment<3>(3 * contact)) : VecX(VecX::Zero(3));
  const VecX a0 = dynamic ? VecX(fem.a().segment<3>(3 * contact)) : VecX(VecX::Zero(3));
  if (!DiscretiseLocalModel(mass, c, k, v0, a0, anchor_force, fem.x().segment<3>(3 * contact),
                            normal, period, out))
    return false;
  out.contact_vertex = static_cast<int>(vertex);
  return true;
}

}  // namespace gipsi
