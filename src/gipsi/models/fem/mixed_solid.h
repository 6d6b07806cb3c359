#pragma once
/// @file
/// `MixedSolid`: nearly or fully incompressible hyperelasticity without locking, quasi-static or
/// dynamic —
/// Taylor–Hood P2–P1 elements (quadratic displacements on 10-node tets, continuous linear
/// pressure on the vertices), the classic inf–sup stable pair, verified on the cardiac-mechanics
/// benchmarks (Land et al., "Verification of cardiac mechanics software: benchmark problems and
/// solutions for testing active and passive material behaviour", Proc. R. Soc. A 471, 2015).
///
/// The law's energy must split as W(F) = W̃(F) + κ/2 (ln J)² (SolidMaterial::
/// log_volumetric_modulus(): NeoHookean, Guccione). The volumetric term is replaced by an
/// independent pressure p (a perturbed Lagrangian; Simo & Taylor, "Quasi-incompressible finite
/// elasticity in principal stretches", CMAME 85, 1991):
///   Π(u, p) = ∫ W̃(F) + p ln J − p²/(2κ) dV − (work of the loads),
/// whose stationarity in p gives p = κ ln J (for finite κ, the same solution as the penalty law
/// in the limit of fine meshes, without its locking), and with `incompressible` the last term
/// is dropped: ln J = 0 in the weak sense and p is the Lagrange multiplier (κ = ∞). Residuals:
///   r_u,a = ∫ (P̃ + p F⁻ᵀ) ∇N_a dV − f_ext,a,     r_p,b = ∫ (ln J − p/κ) L_b dV,
/// with P̃ = ∂W̃/∂F, N_a the P2 and L_b the P1 shape functions, integrated with the 4-point
/// degree-2 rule (quadratic_tets.h). The tangent is exact: the element terms (symmetric,
/// indefinite: [[K, Bᵀ], [B, −M/κ]]) plus the follower-load tangent (not symmetric), solved by
/// a direct LU with pivoting ("umfpack", the default) or, for large meshes, by GMRES with a
/// block preconditioner ("schur_gmres", saddle_point_solver.h: CHOLMOD on the displacement block
/// augmented by γ ∫ (H:∇N_a)(H:∇N_b), each element's pressure mass over its shear modulus for
/// the Schur complement, both from the last tangent); with "ldlt" (finite κ only) the load
/// tangent is symmetrised and Newton converges linearly under large follower loads. The pressure
/// unknown is scaled to the displacements' units (p = s p̃, s = E/h with E the law's small-strain
/// modulus and h the mean edge length) so that Newton's residual and increment tests weigh both
/// alike.
///
/// Loads and constraints come from the boundary conditions on the boundary vertices (as for
/// FemSolid): a displacement on an axis of both ends of a boundary edge holds the edge's
/// midpoint node on that axis at the mean of the two; follower pressure and traction (per
/// current area) act on the 6-node boundary faces; nodal forces act on the vertices. A step
/// ramps the loads and prescribed displacements linearly from the previous step's values (zero
/// before the first step) in `load_steps` increments, and bisects an increment whose Newton
/// solve fails up to `max_bisections` times. Where the held displacements move, Newton starts
/// from the linearised response to them (PredictFromTargets), not from the held nodes moved
/// alone.
///
/// The vertex nodes are the domain mesh's nodes, so every node field, probe and boundary works
/// on the linear mesh (the P2 solution's values at the vertices). The display is the curved
/// boundary: each 6-node face as four triangles through its edge nodes, which follow the P2
/// solution, as do the vertices of an embedded display (mixed_display.cc). Fields: the
/// mechanical fields, "pressure" (node, Pa; the hydrostatic pressure p, positive in tension as
/// p = κ ln J), "volume_ratio" (element, mean J over its quadrature points), "volume" (global,
/// m³, ∫ J dV integrated exactly), "strain_energy" (global, J, ∫ W̃ dV + ∫ κ/2 (ln J)² dV for
/// finite κ), "newton_iterations" (global, last increment).
///
/// Fields "fibre" and "active_tension" (element, read/write; "fibre" reads the first quadrature
/// point's and writes all four, SetFibreAt sets one) give the material axes and
/// an active tension along the fibre (MaterialPoint), ramped from the previous step's values
/// with the loads.
///
/// The state is MixedState (mixed_state.h). Checkpoints save it and the Newton solver's warm
/// start and kept factorisation (a resumed run continues bitwise); a snapshot restore drops the
/// latter (the retry factorises afresh), as for FemSolid.
///
/// Dynamics (`scheme` BackwardEuler or BDF2; implicit_scheme.h): the displacement unknowns
/// carry inertia and mass-proportional damping, r_u += M (a + α v) with the consistent P2 mass
/// M_ab = ∫ ρ N_a N_b dV (integrated exactly, curved elements included: TetRuleDegree7), and
/// the pressure rows are unchanged (the constraint holds at every instant). A dynamic step is
/// one nonlinear solve at the step's loads (no load increments, no bisection: a step that does
/// not converge fails, and the kernel's caller may retry with a smaller step). Gravity ρ g acts
/// as the consistent body force M g, ramped with the loads in quasi-static steps. Prescribed
/// velocities are honoured (the increment that gives them; refused quasi-statically). Fields
/// "velocity" (node, read/write: the vertices'; a write gives the edge nodes the mean of their
/// ends) and "kinetic_energy" (global, ½ vᵀ M v over all P2 nodes).
///
/// Cavities (`cavities`, as for FemSolid; wall_cavity.h): the volume a cavity's curved faces
/// enclose (quadratic_volume.h) and its pressure are the fields "<name>_volume" and
/// "<name>_pressure". An uncoupled cavity's pressure is written from outside and acts on its
/// faces like a boundary pressure. A CavityCoupling makes the pressure an unknown of the step
/// (CavityWall): Newton solves the wall with V(u) = V_b(p), the blood law's end volume, the
/// pressure bordered onto the saddle-point system and its rank-one term ∂V/∂x ⊗ ∂V/∂x / C
/// solved by Woodbury (fem_cavity.cc explains the formulation for FemSolid); the follower load
/// p ∂V/∂x has its exact tangent p ∂²V/∂x² on the faces (the rim caps' share is left out: exact
/// when the rim is held).
///
/// Newmark (average acceleration) starts from the accelerations and pressure that the first
/// step's loads give at rest: [[M, Bᵀ], [B, 0]] (a₀, p₀) = (f_ext − f̃_int − α M v₀, 0) when
/// incompressible (B a₀ = 0: the constraint's second derivative, exact for a body at rest), and
/// with p₀ = κ ln J otherwise (mixed_newmark.cc). Not yet: collision and haptic local models.
/// Units: SI.

#include <memory>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/cavity_law.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/models/fem/mixed_state.h"
#include "gipsi/models/fem/quadratic_tets.h"
#include "gipsi/models/fem/quadratic_volume.h"
#include "gipsi/models/fem/solid_material.h"
#include "gipsi/models/wall_cavity.h"
#include "gipsi/numerics/implicit_scheme.h"
#include "gipsi/numerics/newton.h"
#include "gipsi/numerics/sparse/saddle_point_solver.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Parameters. Plain struct with defaults.
struct MixedSolidParams {
  /// Required; its log_volumetric_modulus() must be positive.
  std::shared_ptr<const SolidMaterial> material;
  /// κ = ∞: J = 1 enforced by a Lagrange-multiplier pressure (the law's κ is not used).
  bool incompressible = false;
  Vec3 fibre = Vec3::UnitX();  ///< uniform fibre direction (reference configuration)
  Vec3 sheet = Vec3::UnitY();  ///< uniform sheet direction (orthogonalised against the fibre)
  int load_steps = 1;          ///< increments per (quasi-static) step
  int max_bisections = 6;      ///< halvings of a failed increment before the step fails
  /// kStatic (quasi-static), kBackwardEuler, kBdf2 or kNewmark (dynamic).
  ImplicitSchemeKind scheme = ImplicitSchemeKind::kStatic;
  double density = 1000;        ///< ρ [kg/m³], for the mass and gravity
  double rayleigh_mass = 0;     ///< α [1/s]: damping force α M v
  Vec3 gravity = Vec3::Zero();  ///< g [m/s²]
  /// Where a dynamic step's Newton solve starts (implicit_scheme.h); a predicted state with an
  /// inverted element falls back to the last step's.
  StepPredictor predictor = StepPredictor::kNone;
  /// Cavities bounded by parts of the boundary (wall_cavity.h), coupled to blood by a
  /// CavityCoupling or loaded by their written pressure.
  std::vector<CavitySpec> cavities;
  NewtonOptions newton;
  LinearSolverOptions linear_solver = [] {
    LinearSolverOptions o;
    o.type = "umfpack";
    o.tolerance = 1e-8;
    return o;
  }();
};

/// Not copyable or movable (a SimObject).
class MixedSolid final : public SimObject, public CavityWall {
 public:
  /// Throws InputError for a mesh without tets, inverted or degenerate tets, a missing law or
  /// one without a split volumetric term, a zero fibre direction, a non-positive density,
  /// several load steps with a dynamic scheme, or a cavity whose region selects no face or whose
  /// rim is not a set of simple loops.
  MixedSolid(std::string name, std::shared_ptr<const Mesh> domain, MixedSolidParams params);

  [[nodiscard]] std::string_view type_name() const override { return "MixedSolid"; }
  [[nodiscard]] const Points& domain_positions() const override { return vertex_positions_; }
  [[nodiscard]] std::string failure_detail() const override { return failure_detail_; }
  /// Assembly and linear-solve time, Newton and linear iterations and factorisations of this
  /// run (`gipsi run --profile`; not saved in checkpoints).
  [[nodiscard]] std::vector<ProfileEntry> ProfileBreakdown() const override;
  /// The P2 mesh, curved where the domain's second-order geometry curves it: VTU series write
  /// VTK_QUADRATIC_TETRA cells with the displacement and position of the edge nodes (pressure
  /// and the other node fields linear along each edge).
  [[nodiscard]] bool GetQuadraticOutput(QuadraticOutput& out) const override;
  [[nodiscard]] bool ReadEdgeNodeField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;

  [[nodiscard]] const MixedSolidParams& params() const { return params_; }
  [[nodiscard]] const QuadraticTets& quadratic_mesh() const { return mesh_; }
  /// Displacements of every P2 node (3 by num_nodes, vertices first).
  [[nodiscard]] Points NodeDisplacements() const;
  /// Pressure at every vertex [Pa].
  [[nodiscard]] VecX Pressures() const;
  /// ∫ J dV over the body [m³] at the current state.
  [[nodiscard]] double CurrentVolume() const;
  /// M x for a field x on the P2 nodes (3 by num_nodes), M the consistent mass [kg].
  [[nodiscard]] Points ApplyMass(const Points& x) const;
  /// Whether the scheme is dynamic (not kStatic).
  [[nodiscard]] bool dynamic() const { return params_.scheme != ImplicitSchemeKind::kStatic; }
  /// Velocities of every P2 node (3 by num_nodes; zero when quasi-static).
  [[nodiscard]] Points NodeVelocities() const;
  /// Statistics of the last Newton solve.
  [[nodiscard]] const NewtonStats& last_newton() const { return state_.last_newton; }
  /// Total Newton iterations and factorisations over all steps (for benchmarks).
  [[nodiscard]] std::int64_t total_newton_iterations() const { return state_.total_iterations; }
  /// Total iterations of an iterative linear solver ("schur_gmres") in this run (not saved).
  [[nodiscard]] std::int64_t total_linear_iterations() const { return total_linear_iterations_; }

  /// The residual r(z) and, if `jacobian` is not null, the Jacobian at the unknowns z =
  /// (u node-major, p̃) for the loads at load fraction s of the current step, with no
  /// constraint applied (for tests: finite-difference checks). False if an element is outside
  /// its law's domain.
  bool EvaluateUnconstrained(const VecX& z, double s, VecX& r, SparseMatrix* jacobian) const;
  /// Number of unknowns (3 × nodes + vertices) and the pressure scale s [Pa/m].
  [[nodiscard]] Index num_unknowns() const { return 3 * mesh_.num_nodes() + mesh_.num_vertices; }
  [[nodiscard]] double pressure_scale() const { return pressure_scale_; }
  /// Sets the fibre at quadrature point q (0..3) of element e (the sheet is re-orthogonalised
  /// against it): for fibre rules evaluated where the element integrates (rule-based fibres
  /// through a wall only one or two tets thick). Preconditions checked.
  void SetFibreAt(Index e, int q, const Vec3& fibre);
  /// Material axes (columns fibre, sheet, normal) at quadrature point q of element e.
  [[nodiscard]] const Mat3& axes_at(Index e, int q) const;
  /// Where quadrature point q (0..3) of element e lies at rest (on the curved element's own
  /// map, Σ N_a X_a). Preconditions checked.
  [[nodiscard]] Vec3 QuadraturePoint(Index e, int q) const;
  /// On a curved mesh, a target in a curved tet gets the reference point L of the tet's own
  /// map (Σ N_a(L) X_a = target, by Newton from the straight tet's barycentrics) instead of the
  /// straight barycentrics, so that probes, embedded displays and FieldCopy read the quadratic
  /// field at the point itself, also beside a curved boundary that bulges past the straight
  /// tets. Straight tets, and targets outside the curved mesh (clamped), keep the straight
  /// map's weights.
  [[nodiscard]] PointMap MapFromNodes(const Points& targets) const override;
  /// The current unknowns z.
  [[nodiscard]] const VecX& unknowns() const { return state_.z; }

  // CavityWall.
  [[nodiscard]] std::vector<std::string> cavity_names() const override {
    return CavityNames(params_.cavities);
  }
  /// Throws InputError for an unknown cavity or one already coupled.
  void AttachCavityLaw(std::string_view cavity, CavityLaw* law) override;
  /// Volume enclosed by cavity i's curved faces at the current state [m³].
  [[nodiscard]] double CavityVolume(std::size_t i) const;
  /// Its pressure [Pa] (solved with the wall when coupled to blood).
  [[nodiscard]] double CavityPressure(std::size_t i) const;
  /// Cavity i's volume as a function of the P2 node positions (its curved faces and rim caps).
  [[nodiscard]] const QuadraticEnclosedVolume& cavity_volume(std::size_t i) const {
    return cavities_.at(i).volume;
  }

  /// The state that evolves (mixed_state.h), bound with BindState.
  [[nodiscard]] const MixedState& state() const { return state_; }

 protected:
  StepStatus DoStep(double t, double dt) override;
  void SaveStateCache(StateWriter& out) const override;
  void RestoreStateCache(StateReader& in) override;
  void DropStateCache() override;
  void StateRestored() override { UpdatePositions(); }
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;

 private:
  /// One load increment as the nonlinear system Newton solves (mixed_solid.cc).
  class Increment;
  static constexpr int kLocal = 34;  // 30 displacement and 4 pressure unknowns per element
  static constexpr int kQuad = 4;    // quadrature points per element
  /// One cavity: the wall's (faces, fields, law) and its curved volume. The work members are
  /// set with every residual.
  struct Cavity {
    WallCavity wall;
    QuadraticEnclosedVolume volume;
    std::vector<int> boundary_faces;  // the boundary face of each of volume.faces()
    mutable VecX gradient;            // ∂V/∂z (the unknowns; zero on held dofs and pressures)
    mutable Points node_gradient;     // ∂V/∂x of the P2 nodes, 3 by nodes
    mutable double volume_residual = 0;  // V(u) − V_b(p)
    mutable double stiffness = 0;        // −dp/dV_b
  };
  /// The increment's residual r(x) at load fraction s (and J's values if `jv` is not null),
  /// x = (z, coupled cavity pressures); false if x is not admissible or a blood law fails.
  bool IncrementResidual(double s, const VecX& x, VecX& r, double* jv);
  bool IncrementResidualOnly(double s, const VecX& x, VecX& r, double* jv);
  /// "schur_gmres" (mixed_schur.cc): the solver, schur_'s values from element_shear_, and
  /// both preconditioner parts handed to the solver after a tangent is assembled.
  std::unique_ptr<LinearSolver> MakeSchurSolver();
  void FillSchur();
  void UpdatePreconditioner();
  /// For each coupled cavity: V and ∂V/∂z at z, the load −p ∂V/∂z into r (and −p ∂²V/∂x² into
  /// J's values if `jv` is not null) at the state's pressure; with `laws`, its blood law's
  /// volume residual and stiffness too (false if the law cannot answer).
  bool AddCavityLoads(const VecX& z, VecX& r, double* jv, bool laws) const;
  [[nodiscard]] int num_low_rank_terms() const { return bordered_; }
  void LowRankTerm(int k, const VecX*& b, double& w) const;
  /// Builds cavities_ from params_.cavities and declares their fields (mixed_cavity.cc).
  void MakeCavities(const Mesh& domain);
  /// Newton's iterate (z, coupled pressures) to and from the state.
  void GiveIterate(VecX& x) const;
  void TakeIterate(const VecX& x);

  /// Element terms of r (and J's values if `jv` is not null) at z and load fraction `load`
  /// (the active tension is ramped with the loads); false if an element is
  /// outside its law's domain. Sets residual_floor_.
  bool Assemble(const VecX& z, double load, VecX& r, double* jv) const;
  /// Material axes at quadrature point q of element e, active tension at load fraction `load`.
  [[nodiscard]] MaterialPoint PointOf(Index e, int q, double load) const;
  /// Adds M (a + α v) of the dynamic step's increment z − x_n (and (c_a + α c_v) M to J).
  void AssembleInertia(const VecX& z, VecX& r, double* jv) const;
  /// Adds −f_ext at load fraction s and its tangent (face loads) at z.
  void AssembleLoads(const VecX& z, double s, VecX& r, double* jv) const;
  /// Zeroes the constrained rows (and columns in J, unit diagonal times diag_scale_).
  void ApplyConstraints(VecX& r, double* jv) const;
  /// This step's loads and constraints (an uncoupled cavity's pressure loads its faces);
  /// returns a boundary vertex with a prescribed velocity
  /// (which MixedSolid does not take), or -1.
  Index GatherLoads();
  void SetTargets(VecX& z, double s) const;
  /// Quasi-static increments whose prescribed displacements move: z becomes the linearised
  /// response at z (the tangent at z, the targets at s as its Dirichlet data), so the free
  /// nodes follow the held ones before Newton starts. False (z unchanged) when nothing moves,
  /// with cavities coupled or the "schur_gmres" solver, or if an element of the prediction is
  /// outside its law's domain or the solve fails.
  bool PredictFromTargets(VecX& z, double s);
  StepStatus Advance(double s0, double s1, int depth);
  /// Newmark's a₀ (mixed_newmark.cc): the accelerations of the first step's loads at the
  /// current state, with the pressure that keeps them admissible; false (failure_detail_ set)
  /// if an element is outside its law's domain or the solve fails.
  bool InitialAcceleration();
  void UpdatePositions();
  /// The default display: each boundary face split at its edge nodes into four triangles,
  /// whose vertices follow the P2 solution (mixed_display.cc).
  void MakeCurvedDisplay();
  /// Adds each display vertex's share of the bows of the edges its map interpolates along
  /// (x_e − (x_a + x_b)/2 times 4 w_a w_b, the P2 interpolation's difference from the linear).
  void CorrectDisplayPositions(DisplayGeometry& display) const override;
  /// Probes at points: the bows of displacement, position and velocity (P2 fields; the
  /// pressure is P1, and nodal forces are not interpolated).
  void CorrectInterpolated(FieldId id, const Eigen::Matrix4Xi& nodes,
                           const Eigen::Matrix4Xd& weights,
                           Eigen::Ref<Eigen::MatrixXd> at) const override;
  void OnDisplayChanged() override;
  /// grad_ and weight_ of curved element e (isoparametric); throws InputError naming the tet
  /// of `domain` if its map from the reference tet is not positive.
  void CurvedElementGeometry(Index e, const Mesh& domain);
  /// F = I + Σ_a u_a ⊗ ∇N_a at quadrature point q of element e for the unknowns z.
  [[nodiscard]] Mat3 DeformationGradient(Index e, int q, const VecX& z) const;
  [[nodiscard]] double ElementEnergy(Index e, const VecX& z) const;
  /// "; … the smallest J … in tet N (centre …)" at the current state, for failure messages.
  [[nodiscard]] std::string MostCompressedElement() const;

  MixedSolidParams params_;
  const SolidMaterial* law_ = nullptr;
  double kappa_ = 0;
  QuadraticTets mesh_;
  std::vector<double> grad_;  // per element and quadrature point: 3 × 10 ∇N (column-major)
  VecX weight_;               // per element and quadrature point: its share of the rest volume
  std::vector<double> mass_;  // per element: the 10 × 10 consistent mass (column-major) [kg]
  VecX gravity_force_;        // M g on the displacement unknowns (3 per node) [N]
  double pressure_scale_ = 1;
  // Boundary faces as 6-node triangles (P2 node ids).
  Eigen::Matrix<int, 6, Eigen::Dynamic> faces_;
  Eigen::Matrix<int, 6, Eigen::Dynamic> face_local_;  // their local numbers in the face's tet
  // Sparse pattern and the value index of every (local row, local column) of every element.
  SparseMatrix jac_;
  std::vector<int> element_value_index_;  // 34 × 34 per element
  std::vector<int> diag_index_;           // per unknown
  // Constraints per P2-node dof: target displacement at s = 0 and s = 1.
  std::vector<std::uint8_t> constrained_;
  std::vector<int> constrained_dofs_;
  VecX target_prev_, target_new_;
  // Per display vertex (CSR): the edge nodes whose bows its position takes, and their weights.
  std::vector<int> display_bow_start_, display_bow_node_;
  std::vector<double> display_bow_weight_;
  // PredictFromTargets' own solver when Newton keeps its factorisation between solves.
  std::unique_ptr<LinearSolver> predictor_solver_;
  // Loads at s = 0 and s = 1.
  VecX force_new_;  // 3 × vertices (the previous step's, s = 0, are state)
  VecX pressure_new_;
  Points traction_new_;
  mutable double residual_floor_ = 0;
  double diag_scale_ = 1;
  bool exact_load_tangent_ = false;  // the linear solver takes nonsymmetric matrices
  MixedState state_;                 // everything that evolves (mixed_state.h)
  VecX z_begin_;
  VecX cavity_pressure_begin_;
  std::vector<Cavity> cavities_;
  mutable Points node_positions_;  // work: rest + displacement of every P2 node
  int bordered_ = 0;               // coupled cavities: Newton's bordered unknowns
  VecX newton_x_, iterate_z_, iterate_r_, predicted_;
  double step_time_ = 0, step_dt_ = 0;
  mutable int failed_cavity_ = -1;
  std::int64_t total_linear_iterations_ = 0;
  mutable double assembly_seconds_ = 0;  // residuals and tangents (IncrementResidual)
  double newton_seconds_ = 0;            // Newton's solves, assembly included
  std::int64_t factorizations_ = 0;
  Points vertex_positions_;
  std::unique_ptr<NewtonSolver> newton_;
  // "schur_gmres": the solver (owned by newton_), its Schur approximation and what it is made of.
  SaddlePointSolver* saddle_ = nullptr;
  SparseMatrix schur_;
  std::vector<int> schur_index_;               // 16 per element: positions in schur_
  std::vector<double> element_pressure_mass_;  // 16 per element: ∫ L_a L_b dV
  mutable VecX element_shear_;                 // per element, from the last tangent
  mutable std::vector<double> augmentation_;   // the K̂ augmentation, at jac_'s positions
  double rest_shear_ = 0;
  std::string failure_detail_;
  MechanicalFieldIds mech_;
  FieldId f_fibre_, f_active_, f_pressure_, f_jacobian_, f_volume_, f_energy_, f_newton_,
      f_kinetic_;
};

/// Registers "MixedSolid".
void RegisterMixedSolid(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
