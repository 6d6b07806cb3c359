#pragma once
/// @file
/// `FemSolid`: nonlinear solid mechanics on a linear (P1) tetrahedral mesh — GiPSi's FEM
/// modeling tool. Any solid law (solid_material.h): small-strain linear, corotational,
/// St. Venant–Kirchhoff, neo-Hookean, Guccione myocardium with fibres and active tension.
///
/// Equations (x node positions, 3N): M a + C v + f_int(x) = f_ext(x), with
///   f_int,a = Σ_e V_e P(F_e) ∇N_a          (P the law's first Piola–Kirchhoff stress)
///   f_ext   = gravity (ρ g per node mass) + nodal forces + external_force field
///             + follower pressure and traction on boundary triangles (surface_loads.h)
///   M lumped (ρV/4 per node) or consistent (ρV/20 (1 + δ_ab)), C = α M + β K_n (Rayleigh, K_n
///   the tangent at the start of the step, so the damping force is linear in v within a step).
/// Time stepping by any ImplicitScheme (Static, BackwardEuler, BDF2, Newmark) and Newton with
/// line search; the tangent is consistent (law tangents, symmetric part of the load tangent).
/// A step whose Newton solve fails is bisected (loads interpolated linearly over the step) up
/// to `max_bisections` times before the step is reported failed with a diagnostic; a solve
/// that is still converging when its iterations run out is given more (newton.h) instead.
/// A stop request (stop_token) is polled before every load increment and Newton iteration;
/// the step is then abandoned (the state of its start restored) and reported as stopped.
/// Kinematic boundary conditions (displacement, velocity per axis on boundary vertices) are
/// imposed exactly; reaction forces are readable as the boundary field "reaction_force".
/// Alternatively the solid is an OdeSystem (numerics/ode.h) and any OdeIntegrator steps it
/// (explicit dynamics, fem_solid_ode.cc): y = [u; v], ẏ = [v; M_L⁻¹(f_ext − f_int − C v)] with
/// the lumped mass, C = α M_L + β K(u) at the stage's state, loads interpolated linearly in time
/// over the step, and constrained axes moving at their prescribed velocity (displacement targets
/// reached exactly at the step's end). Units: SI (m, kg, s, N, Pa).

#include <array>
#include <chrono>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/row_state.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/geometry/enclosed_volume.h"
#include "gipsi/geometry/region.h"
#include "gipsi/models/fem/fem_state.h"
#include "gipsi/models/fem/solid_distribution.h"
#include "gipsi/models/fem/solid_material.h"
#include "gipsi/models/fem/solid_options.h"
#include "gipsi/models/fem/tet_assembly.h"
#include "gipsi/models/wall_cavity.h"
#include "gipsi/numerics/implicit_scheme.h"
#include "gipsi/numerics/newton.h"
#include "gipsi/numerics/ode.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Parameters. Plain struct with defaults.
struct FemParams {
  double density = 1000;                          ///< kg/m³
  std::shared_ptr<const SolidMaterial> material;  ///< required
  bool lumped_mass = false;                       ///< else consistent mass
  double rayleigh_mass = 0;                       ///< α [1/s]
  double rayleigh_stiffness = 0;                  ///< β [s]
  Vec3 gravity = Vec3(0, 0, -9.81);               ///< m/s²
  ImplicitSchemeKind scheme = ImplicitSchemeKind::kBackwardEuler;
  double newmark_beta = 0.25, newmark_gamma = 0.5;  ///< Newmark parameters
  NewtonOptions newton;
  LinearSolverOptions linear_solver;
  int load_steps = 1;      ///< increments per step (quasi-static load stepping)
  int max_bisections = 6;  ///< halvings of a failed increment before the step fails
  /// Where Newton starts each step (dynamic schemes only; an inadmissible predicted state, an
  /// inverted element, falls back to x_n):
  /// - kNone: at x_n;
  /// - kConstantVelocity: at x_n + Δt v_n. For smooth motion (a beating heart) the first
  ///   iterate is then O(Δt² a) from the solution instead of O(Δt v);
  /// - kConstantAcceleration: at the increment the scheme turns into the velocity
  ///   v_n + Δt a_n (x_n + Δt v_n + Δt² a_n for backward Euler), O(Δt³ ȧ) from the solution.
  ///   The heart's muscle then needs 15 % fewer Newton iterations than with constant velocity
  ///   (docs/performance.md).
  using Predictor = StepPredictor;
  Predictor predictor = Predictor::kNone;
  Vec3 fibre = Vec3::UnitX();  ///< uniform fibre direction (reference configuration)
  Vec3 sheet = Vec3::UnitY();  ///< uniform sheet direction (orthogonalised against the fibre)
  /// Cavities (wall_cavity.h): each one's volume is a field, and a pressure written to it acts
  /// as follower pressure on its faces.
  std::vector<CavitySpec> cavities;
  /// Set: the object is one process's part of a solid split over processes
  /// (solid_distribution.h; the domain mesh is the part). Implicit schemes and explicit ODE
  /// integrators: the constructor refuses an implicit ODE integrator (the distributed scene
  /// loader builds such a solid whole on every rank instead). Cavities are selected on the whole
  /// mesh; each process sums its faces' share of their volume and gradient (SplitCavityVolume).
  std::shared_ptr<const SolidDistribution> distribution;
};

/// Time spent in one object's steps, for `gipsi run --profile`. Plain struct.
struct FemProfile {
  double assembly_seconds = 0;  ///< residual and tangent assembly
  double solve_seconds = 0;     ///< linear solves (including factorisations)
  std::int64_t newton_iterations = 0;
  std::int64_t linear_iterations = 0;
  std::int64_t factorizations = 0;  ///< factorisations (or preconditioner set-ups) of the tangent
  std::int64_t steps = 0;
};

/// Not copyable or movable (a SimObject).
class FemSolid final : public SimObject, public CavityWall, public RowState {
 public:
  /// Throws InputError for a mesh without tets, inverted/degenerate tets, a missing material,
  /// or a non-positive density.
  FemSolid(std::string name, std::shared_ptr<const Mesh> domain, FemParams params);
  /// Stepped by `integrator` through the OdeSystem contract instead of an implicit scheme
  /// (params.scheme, newton, linear_solver, load_steps, max_bisections and predictor are
  /// then unused). Also throws InputError unless params.lumped_mass: the ODE needs M⁻¹.
  FemSolid(std::string name, std::shared_ptr<const Mesh> domain, FemParams params,
           std::unique_ptr<OdeIntegrator> integrator);

  [[nodiscard]] std::string_view type_name() const override { return "FemSolid"; }
  [[nodiscard]] const Points& domain_positions() const override { return positions_; }
  [[nodiscard]] std::string failure_detail() const override { return failure_detail_; }

  [[nodiscard]] const FemParams& params() const { return params_; }
  [[nodiscard]] const TetAssembly& assembly() const { return assembly_; }
  [[nodiscard]] Index num_nodes() const { return domain().num_nodes(); }
  [[nodiscard]] Index num_elements() const { return assembly_.num_elements(); }
  /// Positions (3N, node-major), updated after every step and field write.
  [[nodiscard]] const VecX& x() const { return x_; }
  /// Displacements from the rest positions (3N): the state the integrator advances.
  [[nodiscard]] const VecX& u() const { return state_.scheme.x(); }
  /// Velocities and accelerations (3N).
  [[nodiscard]] const VecX& v() const { return state_.scheme.v(); }
  [[nodiscard]] const VecX& a() const { return state_.scheme.a(); }
  /// Statistics of the last Newton solve.
  [[nodiscard]] const NewtonStats& last_newton() const { return state_.last_newton; }
  [[nodiscard]] const FemProfile& profile() const { return profile_; }
  /// The force scale [N] of the last increment's Newton convergence test: the norm of the
  /// applied loads (nodal, weight, surface and cavity pressures) at its first iterate, over the
  /// unconstrained unknowns; Newton converges at tolerance · max(‖r(d₀)‖, this).
  [[nodiscard]] double load_scale() const { return load_scale_; }
  [[nodiscard]] std::vector<ProfileEntry> ProfileBreakdown() const override;
  /// The state that evolves (fem_state.h), bound with BindState: checkpoints save it and the
  /// Newton solver's warm start and kept factorisation (a bitwise continuation needs them);
  /// a snapshot restore drops the latter (fem_solid_state.cc).
  [[nodiscard]] const FemState& state() const { return state_; }
  /// RowState (fem_solid_rows.cc): a split solid's part moves to another partition.
  [[nodiscard]] StateRows ReadStateRows(StateReader& in, const ItemCounts& counts) const override;
  void WriteStateRows(StateWriter& out, const StateRows& rows) const override;

  /// The OdeSystem contract (y = [u; v], 6N; fem_solid_ode.cc). CalcDerivative evaluates the
  /// loads at the fraction (t − t_n)/Δt of the step in progress (1 outside a step), and gives
  /// constrained axes zero acceleration. An element outside its law's domain at a stage makes
  /// the step fail after the integrator returns (the state is then left at the step's start).
  [[nodiscard]] Index ode_size() const { return 6 * num_nodes(); }
  [[nodiscard]] Index ode_num_positions() const { return 3 * num_nodes(); }
  void CalcDerivative(double t, Eigen::Ref<const VecX> y, Eigen::Ref<VecX> ydot) const;
  /// The integrator that steps the ODE, or null when an implicit scheme does.
  [[nodiscard]] const OdeIntegrator* ode_integrator() const { return ode_integrator_.get(); }
  /// Stability limit of explicit (central-difference-like) steps, 2/ω_max, with ω_max² bounded
  /// by the largest Gershgorin row sum of M_L⁻¹ K at the rest shape [s]: conservative.
  [[nodiscard]] double stable_dt_estimate() const;

  /// Internal forces f_int(x) (3N) for positions x (3N); false if an element is outside its
  /// law's domain. For tests and connectors.
  bool CalcInternalForces(const VecX& x, VecX& f) const;
  /// The tangent stiffness K = ∂f_int/∂x at positions x, in assembly().MakePattern() layout.
  bool CalcStiffness(const VecX& x, SparseMatrix& K) const;
  /// Σ_e V_e W(F_e) [J].
  [[nodiscard]] double StrainEnergy() const;
  /// ½ vᵀ M v [J].
  [[nodiscard]] double KineticEnergy() const;
  /// Gravitational potential energy relative to the rest configuration, −Σ m g·(x − X) [J].
  [[nodiscard]] double GravityEnergy() const;
  /// Number of elements with det F <= 0 at the current state.
  [[nodiscard]] Index CountInvertedElements() const;
  /// Cauchy stress of element e at the current state (zero if outside the law's domain).
  [[nodiscard]] Mat3 CauchyStress(Index e) const;
  /// Volume of cavity i (FemParams::cavities order) at the current state [m³]; an open rim is
  /// capped (EnclosedVolume).
  [[nodiscard]] double CavityVolume(std::size_t i) const;
  /// Couples cavity `cavity` to blood (cavity_law.h): each step then solves for the cavity
  /// pressure p with the displacements so that the enclosed volume equals the law's end volume
  /// at p (monolithic; the pressure's dependence on the wall enters the Newton tangent as a
  /// rank-one term). Its pressure field becomes read-only in effect (writes are ignored).
  void AttachCavityLaw(std::string_view cavity, CavityLaw* law) override;
  [[nodiscard]] std::vector<std::string> cavity_names() const override;
  /// The cavity's pressure [Pa]: written (pressure mode) or solved (coupled to a CavityLaw).
  [[nodiscard]] double CavityPressure(std::size_t i) const;

 protected:
  StepStatus DoStep(double t, double dt) override;
  void SaveStateCache(StateWriter& out) const override;
  void RestoreStateCache(StateReader& in) override;
  void DropStateCache() override;
  void StateRestored() override { UpdatePositions(); }
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  [[nodiscard]] const double* DoFieldMemory(FieldId id) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;

 private:
  /// One load increment as the nonlinear system Newton solves (fem_solid.cc).
  class Increment;
  // The increment's residual r(d) at load fraction s (0: the previous step's loads, 1: this
  // step's) as a function of d = x − x_n; false if d is not admissible.
  bool IncrementResidual(double s, const VecX& d, VecX& r);
  // Its residual and tangent; if `damping_tangent`, the element tangent at d also becomes K_n
  // of Rayleigh damping (the tangent at the increment's first iterate).
  bool IncrementResidualAndJacobian(double s, const VecX& d, VecX& r, SparseMatrix& J,
                                    bool damping_tangent);
  /// Newton's iterate (d, p) → d in bordered_d_ and the coupled cavities' pressures.
  const VecX& TakeIterate(const VecX& x);
  /// d_ and the coupled cavities' pressures → Newton's iterate (d, p).
  void GiveIterate(VecX& x) const;
  /// The residual r_u in bordered_r_ and the cavities' volume residuals → Newton's r.
  void GiveResidual(VecX& r) const;
  [[nodiscard]] int num_low_rank_terms() const;
  void LowRankTerm(int k, const VecX*& b, double& w) const;

  /// f_int (and K values if `k_values` is not null) at displacements u; marks invalid
  /// elements.
  bool AssembleElements(const double* u, VecX& f, double* k_values) const;
  /// External loads at displacements u and load fraction s (0: the previous step's loads, 1:
  /// this step's) into f_ext_.
  void AssembleExternal(const double* u, double s) const;
  /// Refreshes x_ and positions_ from the displacements.
  void UpdatePositions();
  /// Residual from f_int_ and f_ext_ plus inertia and damping for increment d.
  void FinishResidual(const VecX& d, VecX& r);
  /// Reads the boundary conditions into the step's targets.
  void GatherTargets();
  StepStatus Advance(double s0, double s1, double dt, int depth);
  /// A step through the OdeSystem contract (fem_solid_ode.cc).
  StepStatus StepOde(double t, double dt);
  [[nodiscard]] MaterialPoint PointOf(Index e) const;
  /// J −= sym(∂f/∂x) of face f's follower pressure p and traction t at displacements u.
  void AddFaceLoadTangent(Index f, const double* u, double p, const Vec3& t, double* jv) const;
  /// Coupled cavities (fem_cavity.cc): for each one's pressure p (Newton's bordered unknown)
  /// and displacements u, adds p ∂V/∂x to f_ext_ and stores ∂V/∂x (zero on constrained dofs),
  /// V(u) − V_b(p) and −∂p/∂V_b; false if a law fails.
  bool AddCoupledCavityLoads(const double* u);
  /// Their follower tangent (the rank-one term's weight comes with the residual).
  void AddCoupledCavityTangent(const double* u, double* jv);
  /// Adds p ∂V/∂x of every coupled cavity at the current positions to f (every dof, the held
  /// ones too: for reaction forces).
  void AddCoupledCavityForces(VecX& f) const;
  /// The norm of the applied loads last assembled (f_ext_: nodal, surface and cavity
  /// pressures) over the free unknowns.
  [[nodiscard]] double AppliedLoadNorm() const;
  /// Back to the pressures at the start of the step (after a failed Newton solve).
  void RestoreCavityPressures();
  void InitialAcceleration();
  /// ‖v‖ of a vector of partial sums (3 per local node) made whole over the processes, over
  /// the free unknowns when `free_only`; v.norm() when the object is not distributed.
  [[nodiscard]] double WholeNorm(const VecX& v, bool free_only) const;
  /// Sums `values` over the processes (`max`: their maximum) when distributed.
  void Reduce(std::span<double> values, bool max = false) const {
    if (dist_) dist_->Reduce(values, max);
  }

  FemParams params_;
  const SolidDistribution* dist_ = nullptr;  // params_.distribution
  TetAssembly assembly_;
  const SolidMaterial* law_ = nullptr;
  VecX lumped_mass_;  // per node
  // Split over processes (ODE path): the lumped mass summed over the processes at shared nodes.
  VecX whole_lumped_mass_;
  SparseMatrix mass_;  // consistent mass (pattern layout); empty values if lumped
  SparseMatrix jac_;   // Newton matrix
  // K_n for Rayleigh β (implicit schemes); the stage tangent K(u) under an ODE integrator.
  mutable SparseMatrix damping_k_;
  FemState state_;  // everything that evolves (fem_state.h)
  ImplicitScheme saved_scheme_;
  ImplicitScheme begin_scheme_;  // at the start of the step (a stop abandons the step)
  std::unique_ptr<NewtonSolver> newton_;
  FemProfile profile_;
  // Explicit dynamics through the ODE contract (null: the implicit scheme steps).
  std::unique_ptr<OdeIntegrator> ode_integrator_;
  VecX ode_y_;                        // 6N: [u; v] of the step in progress (work)
  double ode_t0_ = 0, ode_dt_ = 0;    // the step in progress (dt 0: loads at s = 1)
  mutable bool ode_invalid_ = false;  // a stage met an element outside its law's domain

  // This step's loads (s = 1; the previous step's, s = 0, are state), interpolated at the
  // increment's load fraction.
  VecX f_nodal_new_;  // 3N: gravity + nodal forces + external_force
  VecX pressure_new_;
  Points traction_new_;
  // Constraints: mask per dof, displacement target (absolute position) or velocity.
  std::vector<std::uint8_t> constraint_;  // 0 free, 1 displacement, 2 velocity
  VecX target_, x_begin_;
  std::vector<int> constrained_dofs_;
  std::vector<std::array<int, 3>> face_local_;  // local indices of face vertices in its tet
  double load_scale_ = 0;                       // of the last increment solved (a statistic)

  // Work buffers (3N unless noted).
  mutable VecX f_int_, f_ext_, work_, work2_;
  mutable std::vector<std::uint8_t> invalid_;  // per element
  mutable VecX element_force_sum_;             // per element Σ|f_e| (round-off floor)
  mutable double residual_floor_ = 0;
  mutable Index first_invalid_ = -1;
  mutable std::int64_t invalid_id_ = -1;  // its identifier (the smallest over the processes)
  mutable VecX whole_work_;               // WholeNorm's
  // The element loops of the residual and of the residual with the tangent, on the team or
  // serially, whichever has been faster lately (a busy neighbour makes each region wait).
  mutable AdaptiveParallel residual_team_, tangent_team_;
  VecX d_;
  VecX rest_;  // 3N rest positions
  VecX x_;     // 3N current positions
  Points positions_;
  std::string failure_detail_;

  struct Cavity : WallCavity {
    explicit Cavity(WallCavity wall) : WallCavity(std::move(wall)) {}
    double pressure_begin = 0;   // at the start of the step
    VecX gradient{};             // 3N: ∂V/∂x, zero on constrained dofs (coupled)
    double volume_residual = 0;  // V(u) − V_b(p) at the last residual (coupled) [m³]
    // Distributed: `nodes` and the volume are the whole cavity's (whole-mesh nodes), `faces`
    // the part's; the local node of each cavity vertex (-1: not on this rank), the surface
    // triangles of this rank's faces and, per rim loop, the rim half-edges of those triangles
    // (each triangle and half-edge is on exactly one rank).
    std::vector<int> local_node;
    std::vector<int> my_triangles;
    std::vector<std::vector<std::pair<int, int>>> my_loops;
  };
  /// Builds cavities_ from params_.cavities on `domain` and its boundary `bnd` (a split
  /// solid's on the whole mesh, or selected on the parts without it: SelectWholeFaces), and
  /// for a split solid each cavity's faces, nodes and rim half-edges on this part.
  void MakeCavities(const Mesh& domain, const BoundarySurface& bnd);
  /// Cavity c's vertex positions at displacements u (3 per local node) into its `positions`.
  /// Serial only.
  void CavityPositions(const Cavity& cavity, const double* u) const;
  /// Distributed: the whole cavity's volume at displacements u (3 per local node) and, with
  /// `gradient`, ∂V/∂x whole at every local node (3 per node). Each rank sums its faces and its
  /// part of the rim caps; the rim centroids, the volume and ∂V/∂c are reductions and the
  /// gradient is summed at shared nodes, so the ranks exchange O(rim loops) numbers, not the
  /// surface. Collective.
  double SplitCavityVolume(const Cavity& cavity, const double* u, VecX* gradient) const;
  /// The local node of cavity vertex k (-1: none on this rank).
  [[nodiscard]] int CavityNode(const Cavity& cavity, std::size_t k) const {
    return dist_ ? cavity.local_node[k] : cavity.nodes[k];
  }
  mutable VecX cavity_gradient_;  // SplitCavityVolume's gradient for the forces
  std::vector<Cavity> cavities_;
  double step_time_ = 0, step_dt_ = 0;   // of the step in progress (the laws' interval)
  int failed_cavity_ = -1;               // whose law could not answer in the last solve
  bool cavity_follower_tangent_ = true;  // the solver takes indefinite matrices
  // Coupled cavities are Newton's bordered unknowns (NonlinearSystem::num_bordered): its
  // iterate is (d, p) in newton_x_; the increment's residual works on the sparse part in
  // bordered_d_ and bordered_r_.
  int bordered_ = 0;
  VecX newton_x_, bordered_d_, bordered_r_;

  MechanicalFieldIds mech_;
  FieldId f_fibre_, f_active_, f_nodal_active_, f_von_mises_, f_jacobian_, f_kinetic_,
      f_strain_energy_, f_newton_, f_inverted_, f_volume_;
};

/// A "FemSolid" object's scene keys, parsed (fem_solid_factory.cc; keys in
/// docs/scene-format.md): the serial factory's and the distributed one's
/// (parallel/distributed_types.cc). Movable.
struct FemSolidSpec {
  FemParams params;
  std::unique_ptr<OdeIntegrator> ode;  ///< an explicit integrator; null: params.scheme steps
  SolidFibreRule fibre_rule;
  /// The solver of distributed runs: "linear_solver" with the "parallel" block's
  /// "linear_solver" keys over it; CG with no preconditioner named in either takes "amg".
  LinearSolverOptions distributed_linear;
};
/// Checks the object's keys and parses them; throws InputError naming the JSON path of a bad
/// one.
[[nodiscard]] FemSolidSpec ParseFemSolidSpec(const ObjectBuildContext& ctx);

/// Registers "FemSolid".
void RegisterFemSolid(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
