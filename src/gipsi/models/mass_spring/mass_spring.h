#pragma once
/// @file
/// Mass-spring-damper tissue: GiPSi's first modeling tool. Springs on the edges of a tet or
/// triangle mesh, lumped masses from density and element volume (or area × thickness), gravity,
/// drag, and the boundary conditions of its boundary surface. Stepped by any explicit
/// integrator through the OdeSystem contract.
///
/// Equations (node i with lumped mass m_i, position q_i, velocity v_i):
///   m_i dv_i/dt = Σ_springs f_s + m_i g − c_drag m_i v_i + f_ext,i
///   spring s = (a, b), d = q_b − q_a, L = |d|, n = d / L:
///   f_s on a = [T(L; L0, k) + c ((v_b − v_a)·n)] n, and −f_s on b,
/// with T the spring law's tension (Hooke: k (L − L0); see spring_law.h).
/// Units: SI (m, kg, s, N).

#include <memory>

#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/models/mass_spring/spring_law.h"
#include "gipsi/numerics/ode.h"

namespace gipsi {

/// Parameters; plain struct with defaults.
struct MassSpringParams {
  double density = 1000;             ///< kg/m³
  double thickness = 1e-3;           ///< m; for triangle (sheet) domains only
  double stiffness = 100;            ///< N/m per spring
  double damping = 0;                ///< N·s/m per spring, along the spring
  double drag = 0;                   ///< 1/s, mass-proportional damping
  Vec3 gravity = Vec3(0, 0, -9.81);  ///< m/s²
  /// A step that stretches any spring beyond this multiple of its rest length is reported as
  /// divergence (an explicit step that was too large), before values overflow.
  double max_stretch = 100;
  /// The spring law; null means Hooke.
  std::shared_ptr<const SpringLaw> law;
};

/// Not copyable or movable (a SimObject).
class MassSpring final : public SimObject {
 public:
  /// Builds springs from the unique edges of `domain`'s tets (or triangles if it has none) and
  /// lumped masses. Throws InputError if a node belongs to no element or a spring has zero rest
  /// length.
  MassSpring(std::string name, std::shared_ptr<const Mesh> domain, const MassSpringParams& params,
             std::unique_ptr<ExplicitIntegrator> integrator);

  /// A spring network without elements (a thread, a chain, a single spring): `nodes` 3 by N,
  /// `springs` 2 by S node pairs, `masses` N positive masses [kg]. Every node is a boundary
  /// vertex (there are no boundary triangles), so any node can carry conditions. `density` and
  /// `thickness` are unused. Throws InputError for bad indices, zero rest lengths or masses.
  MassSpring(std::string name, const Points& nodes, const Eigen::Matrix2Xi& springs,
             const VecX& masses, const MassSpringParams& params,
             std::unique_ptr<ExplicitIntegrator> integrator);

  [[nodiscard]] std::string_view type_name() const override { return "MassSpring"; }
  [[nodiscard]] const Points& domain_positions() const override { return positions_; }
  void SaveObjectState(StateWriter& out) const override;
  void RestoreObjectState(StateReader& in) override;

  // --- OdeSystem contract: x = [q (3N); v (3N)] ---
  [[nodiscard]] Index ode_size() const { return 6 * num_nodes(); }
  [[nodiscard]] Index ode_num_positions() const { return 3 * num_nodes(); }
  void CalcDerivative(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const;

  [[nodiscard]] Index num_nodes() const { return domain().num_nodes(); }
  [[nodiscard]] Index num_springs() const { return springs_.cols(); }
  /// 2 by S node pairs.
  [[nodiscard]] const Eigen::Matrix2Xi& springs() const { return springs_; }
  [[nodiscard]] const VecX& masses() const { return mass_; }
  [[nodiscard]] const VecX& rest_lengths() const { return rest_length_; }
  [[nodiscard]] const MassSpringParams& params() const { return params_; }
  /// Full state [q; v] (6N).
  [[nodiscard]] const VecX& state() const { return x_; }
  /// Largest stable explicit time step estimate at rest, 2 / ω_max with ω_max² ≈ 4 max_i Σ k / m_i
  /// (a strain-stiffening law lowers the limit as springs stretch).
  [[nodiscard]] double stable_dt_estimate() const;

  [[nodiscard]] double KineticEnergy() const;
  /// Spring energy plus gravitational energy (relative to the rest configuration).
  [[nodiscard]] double PotentialEnergy() const;
  [[nodiscard]] Vec3 Momentum() const;

 protected:
  StepStatus DoStep(double t, double dt) override;
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;

 private:
  /// Total force on every node (3N) at state x, without constraint handling.
  void CalcForces(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> f) const;
  /// Applies the boundary conditions' kinematic constraints to x before a step.
  void ApplyConstraints(double dt);
  StepStatus CheckState() const;
  /// Rest lengths, state, buffers and fields, once springs_ and mass_ are set.
  void Finish();

  MassSpringParams params_;
  bool hooke_ = true;  // params_.law is HookeSpring (inlined in CalcForces)
  std::unique_ptr<ExplicitIntegrator> integrator_;
  Eigen::Matrix2Xi springs_;
  VecX rest_length_;
  VecX mass_;
  VecX x_;                 // [q; v]
  Points positions_;       // q as 3 by N (kept in sync)
  Points external_force_;  // volume-coupling input, 3 by N
  mutable VecX force_;     // work buffer, 3N
  MechanicalFieldIds mech_;
  FieldId f_mass_;
  FieldId f_kinetic_, f_potential_, f_momentum_;
};

/// Registers "MassSpring" with the registry.
void RegisterMassSpring(TypeRegistry& registry);

}  // namespace gipsi
