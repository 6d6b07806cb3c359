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
/// Units: SI (m, kg, s, N, Pa).
///
/// Heart-muscle extensions (a mass-spring variant of the GiPSi heart's muscle):
///
/// *Volume term.* With `volume_stiffness` K > 0 each tet e adds the energy
/// (K/2) |V0_e| (ln J_e)², J_e = V_e/V0_e: FemSolid's volumetric Guccione term, as a volume
/// spring (after the volume constraints of Teschner et al., "A versatile and robust model for
/// geometrically complex deformable solids", CGI 2004). Muscle is nearly
/// incompressible: without this a contracting spring wall shrinks as a whole instead of
/// thickening, and the thick-wall Laplace balance that ends ejection (the pressure a wall of
/// tension T holds grows like T ln(r_epi/r_endo) as the endocardium moves in and the wall
/// thickens) never comes: the cavity either barely ejects or collapses.
///
/// *Active tension.* A per-node field "nodal_active_tension" T [Pa] (written by an
/// excitation–contraction connector) and a fibre direction f_e per tet (the "fibre" field, uniform
/// or rule-based like FemSolid's). Spring s = (a, b) pulls its nodes together with the extra
/// tension T_s w_s along its current direction, T_s = (T_a + T_b)/2 and the weight
///   w_s = Σ_{tets e ∋ s} c_e (V_e/6) (d̂_s·f_e)² / L_s,   c_e = 6 / Σ_{edges r of e} (d̂_r·f_e)⁴
/// (d̂, L the rest direction and length, V_e the tet's rest volume). Why c_e: cut a block whose
/// tets each lie between two node planes x = x_i, x_{i+1} (spacing h) with the fibre along x;
/// the springs crossing the cut are exactly the edges of that layer not lying in a plane, each
/// with d̂·x̂ = h/L, so the force across the cut is Σ T w_s (d̂·x̂) = (T/h) Σ_e c_e (V_e/6)
/// Σ_r (d̂_r·f)⁴ = (T/h) Σ_e V_e = T × (cut area): the stress T f ⊗ f exactly, on any such mesh
/// (tests/models/mass_spring/mass_spring_active_test.cc checks it). For edge directions spread
/// uniformly over the sphere ⟨(d̂·f)⁴⟩ = 1/5, so c_e ≈ 5 on average.
/// Limits: this is a force model, not a stress model. Besides the volume term there is no
/// transverse (Poisson) coupling, so how much a contracting wall thickens depends on the volume
/// term and the cross-fibre springs; shear along the fibre is resisted only by the passive
/// springs; the weights use the rest geometry, and the force does not scale with the fibre
/// stretch λ (FemSolid's second Piola–Kirchhoff active stress T f ⊗ f pulls with T λ per
/// reference area), so a shortened wall keeps more active force than FemSolid's; and only
/// the force across a section normal to the fibres matches
/// the stress T f ⊗ f exactly (oblique sections see the mesh's edge directions).
///
/// *Cavities.* A cavity (e.g. the endocardium) is a set of boundary faces, capped at an open
/// rim like FemSolid's (enclosed_volume.h); fields "<name>_volume" [m³] and "<name>_pressure"
/// [Pa]. The pressure acts as the follower load p ∂V/∂x on the cavity's nodes (the cap's share
/// goes to the rim, so a cavity's pressure has no resultant: the cap stands for the closed
/// valves, which hand the pressure on the valve plane to the rim). A written pressure is
/// evaluated at the integrator's stage positions. Coupled to blood (AttachCavityLaw, the
/// CavityCoupling connector), each step solves for p with the wall: with ∂V/∂x evaluated at the
/// *start* of the step (g, zero on held axes) and q*, v* the symplectic-Euler step with p = 0,
///   v⁺ = v* + p dt M⁻¹ g,   q⁺ = q* + p dt² M⁻¹ g        (exact for symplectic Euler, whose
/// forces are those of the start state), and p solves the scalar equation V(q⁺(p)) = V_b(p),
/// V_b the law's end volume (bracketed Illinois iteration to 1e-13 of the volume). This is
/// implicit in the pressure, so the near-incompressible blood of the isovolumetric phases does
/// not limit the explicit step. Only SymplecticEuler is supported for coupled cavities (for
/// explicit Euler q⁺ does not depend on p; for RK4 it is not affine in p), and coupled cavities
/// must not share nodes (each is solved on its own). The law answers for the object's own step
/// [t, t + dt]: the blood must step with the same dt right after the wall (the CavityCoupling's
/// order), so a MassSpring coupled to blood runs at the blood's rate; it does not sub-step
/// inside the blood's step (a law asked at a time the blood is not at fails the step with a
/// diagnostic).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/geometry/enclosed_volume.h"
#include "gipsi/geometry/region.h"
#include "gipsi/models/mass_spring/spring_law.h"
#include "gipsi/models/wall_cavity.h"
#include "gipsi/numerics/ode.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A cavity's state. Copyable.
struct MassSpringCavityState {
  double pressure = 0;    ///< [Pa]: written through the field, or solved when coupled
  double compliance = 0;  ///< −dV_b/dp of the coupled law at the last solve [m³/Pa]

  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("pressure", s.pressure);
    v("compliance", s.compliance);
  }
};

/// What a MassSpring carries from one step to the next, as a state value type
/// (gipsi/base/state_value.h); the rest is its model (springs, rest lengths, masses) or derived
/// from this (positions, the springs' active weights, which follow the fibres). Copyable.
/// Shapes: N nodes, E tets.
struct MassSpringState {
  static constexpr std::string_view kTag = "MassSpringState";
  static constexpr std::uint32_t kVersion = 1;
  VecX x;                     ///< [q; v], 6N: positions then velocities
  Points external_force;      ///< 3 by N [N], the volume-coupling input
  VecX nodal_active_tension;  ///< per node [Pa]
  Stamped<Points> fibres;     ///< 3 by E, a unit fibre per tet (rarely written)
  std::vector<MassSpringCavityState> cavities;

  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("x", s.x, Shape::kFixed);
    v("external_force", s.external_force, Shape::kFixed);
    v("nodal_active_tension", s.nodal_active_tension, Shape::kFixed);
    v("fibres", s.fibres, Shape::kFixed);
    v("cavities", s.cavities, Shape::kFixed);
  }
};

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
  /// K [Pa]: each tet resists a change of its volume with the energy (K/2) |V0| (ln J)²,
  /// J = V/V0 (a bulk modulus, the volumetric term of FemSolid's Guccione law; 0: off, the
  /// classic spring network). A tet inverted by a step (J ≤ 0) stops the run as diverged.
  /// Tet domains only.
  double volume_stiffness = 0;
  /// Uniform fibre direction of every tet (reference configuration; normalised); per-tet fibres
  /// can be written to the "fibre" field. Only used by the active tension.
  Vec3 fibre = Vec3::UnitX();
  /// Cavities bounded by boundary faces (tet domains), as FemSolid's.
  std::vector<CavitySpec> cavities;  ///< wall_cavity.h
};

/// Not copyable or movable (a SimObject).
class MassSpring final : public SimObject, public CavityWall {
 public:
  /// Builds springs from the unique edges of `domain`'s tets (or triangles if it has none) and
  /// lumped masses. Throws InputError if a node belongs to no element or a spring has zero rest
  /// length.
  MassSpring(std::string name, std::shared_ptr<const Mesh> domain, const MassSpringParams& params,
             std::unique_ptr<OdeIntegrator> integrator);

  /// A spring network without elements (a thread, a chain, a single spring): `nodes` 3 by N,
  /// `springs` 2 by S node pairs, `masses` N positive masses [kg]. Every node is a boundary
  /// vertex (there are no boundary triangles), so any node can carry conditions. `density` and
  /// `thickness` are unused. Throws InputError for bad indices, zero rest lengths or masses.
  MassSpring(std::string name, const Points& nodes, const Eigen::Matrix2Xi& springs,
             const VecX& masses, const MassSpringParams& params,
             std::unique_ptr<OdeIntegrator> integrator);

  [[nodiscard]] std::string_view type_name() const override { return "MassSpring"; }
  [[nodiscard]] const Points& domain_positions() const override { return positions_; }

  // --- OdeSystem contract: x = [q (3N); v (3N)] ---
  [[nodiscard]] Index ode_size() const { return 6 * num_nodes(); }
  [[nodiscard]] Index ode_num_positions() const { return 3 * num_nodes(); }
  void CalcDerivative(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const;

  [[nodiscard]] Index num_nodes() const { return domain().num_nodes(); }
  [[nodiscard]] Index num_springs() const { return springs_.cols(); }
  /// 2 by S node pairs.
  [[nodiscard]] const Eigen::Matrix2Xi& springs() const { return springs_; }
  /// The springs.
  [[nodiscard]] Eigen::Matrix2Xi DisplaySegments() const override { return springs_; }
  [[nodiscard]] const VecX& masses() const { return mass_; }
  [[nodiscard]] const VecX& rest_lengths() const { return rest_length_; }
  [[nodiscard]] const MassSpringParams& params() const { return params_; }
  /// The integrator that steps [q; v] (any OdeIntegrator: explicit or implicit).
  [[nodiscard]] const OdeIntegrator& integrator() const { return *integrator_; }
  /// Full state [q; v] (6N).
  [[nodiscard]] const MassSpringState& state() const { return state_; }
  /// Largest stable explicit time step estimate at rest, 2 / ω_max with ω_max² ≈ 4 max_i Σ k / m_i
  /// (a strain-stiffening law lowers the limit as springs stretch).
  [[nodiscard]] double stable_dt_estimate() const;

  /// Active weight w_s [m²] of every spring (see the file comment); zero for element-free
  /// networks.
  [[nodiscard]] const VecX& active_weights() const { return active_weight_; }
  /// Volume of cavity i (MassSpringParams::cavities order) at the current positions [m³].
  [[nodiscard]] double CavityVolume(std::size_t i) const;
  /// The pressure of cavity i [Pa]: written, or solved when coupled to a CavityLaw.
  [[nodiscard]] double CavityPressure(std::size_t i) const;
  /// Couples cavity `cavity` to blood (see the file comment). Throws InputError if there is no
  /// such cavity, it is already coupled, it shares a node with another coupled cavity, or the
  /// integrator is not SymplecticEuler.
  void AttachCavityLaw(std::string_view cavity, CavityLaw* law) override;
  [[nodiscard]] std::vector<std::string> cavity_names() const override;
  [[nodiscard]] std::string failure_detail() const override { return failure_detail_; }

  [[nodiscard]] double KineticEnergy() const;
  /// Spring energy plus gravitational energy (relative to the rest configuration).
  [[nodiscard]] double PotentialEnergy() const;
  [[nodiscard]] Vec3 Momentum() const;

 protected:
  /// After a checkpoint or snapshot replaced the bound state (BindState): positions,
  /// any_active_, and the active weights if the fibres changed.
  void StateRestored() override;
  StepStatus DoStep(double t, double dt) override;
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  [[nodiscard]] const double* DoFieldMemory(FieldId id) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;

 private:
  /// Which cavity pressures a force evaluation includes: all, or all but the coupled ones (the
  /// predictor of a step with coupled cavities, which solves their pressures after it).
  enum class CoupledPressures : std::uint8_t { kIncluded, kLeftOut };
  /// The ODE a step integrates: CalcDerivative with the coupled pressures included or not.
  struct StepOde;
  /// Total force on every node (3N) at state x, without constraint handling.
  void CalcForces(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> f,
                  CoupledPressures coupled = CoupledPressures::kIncluded) const;
  void CalcDerivative(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot,
                      CoupledPressures coupled) const;
  /// Applies the boundary conditions' kinematic constraints to x before a step.
  void ApplyConstraints(double dt);
  StepStatus CheckState() const;
  /// Rest lengths, state, buffers and fields, once springs_ and mass_ are set.
  void Finish();
  /// Recomputes active_weight_ from the tets, rest geometry and fibres_ (mass_spring_muscle.cc).
  void UpdateActiveWeights();
  /// Adds the tets' volume forces at positions q (3N) to f (mass_spring_muscle.cc).
  void AddVolumeForces(Eigen::Ref<const VecX> q, Eigen::Ref<VecX> f) const;
  /// Σ_e (K/2) |V0| (ln J)² at the current positions [J].
  [[nodiscard]] double VolumeEnergy() const;
  /// The first tet with J ≤ 0 at the current positions if volume_stiffness > 0, else −1.
  [[nodiscard]] Index FirstInvertedTet() const;
  /// Declares the cavities of params_ and their fields (mass_spring_cavity.cc).
  void SetUpCavities();
  /// Adds p ∂V/∂x of every cavity at positions q (3N) to f; coupled ones only if
  /// `include_coupled`.
  void AddCavityForces(Eigen::Ref<const VecX> q, Eigen::Ref<VecX> f, bool include_coupled) const;
  /// ∂V/∂x at the start of the step (g) of every coupled cavity, zero on held axes.
  void BeginCoupledStep();
  /// Solves each coupled cavity's pressure after the p = 0 step and moves the state by it; false
  /// (with failure_detail_ set) if a law cannot answer or no pressure fits.
  bool SolveCoupledCavities(double t, double dt);

  MassSpringParams params_;
  bool hooke_ = true;  // params_.law is HookeSpring (inlined in CalcForces)
  std::unique_ptr<OdeIntegrator> integrator_;
  Eigen::Matrix2Xi springs_;
  VecX rest_length_;
  VecX mass_;
  MassSpringState state_;
  Points positions_;    // q as 3 by N (kept in sync with state_.x)
  mutable VecX force_;  // work buffer, 3N
  MechanicalFieldIds mech_;
  FieldId f_mass_;
  FieldId f_kinetic_, f_potential_, f_momentum_;
  FieldId f_fibre_, f_nodal_active_;

  VecX tet_rest_volume_;             // signed, per tet
  VecX active_weight_;               // per spring [m²], from state_.fibres (E = 0: no fibres)
  std::uint64_t weights_stamp_ = 0;  // state_.fibres' stamp active_weight_ was computed from
  bool any_active_ = false;          // some node has non-zero tension

  struct Cavity : WallCavity {
    explicit Cavity(WallCavity wall)
        : WallCavity(std::move(wall)), step_gradient(Points::Zero(3, positions.cols())) {}
    Points step_gradient;  // g at the start of the step, zero on held axes
  };
  std::vector<Cavity> cavities_;
  bool symplectic_ = false;  // the integrator is SymplecticEuler
  std::string failure_detail_;
};

/// Registers "MassSpring" with the registry.
void RegisterMassSpring(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
