#pragma once
/// @file
/// `EpTissue`: the part of every monodomain (bioelectricity) simulation object that does not
/// depend on how space is discretised — cell states, operator splitting, stimulus protocols,
/// voltage clamps, activation-time and APD maps, fields, divergence checks. A subclass owns the
/// geometry and supplies the diffusion operator: a mass (lumped vector or consistent matrix) and
/// a stiffness matrix K_ij = ∫ ∇φ_i · D ∇φ_j with D = σ/(χ Cm) (P1 tets: `Monodomain`; a
/// regular grid: `GridMonodomain`).
///
/// The monodomain equation χ (Cm ∂V/∂t + I_ion(V, s)) = ∇·(σ∇V) + I_vol, divided by χ Cm, is
///   ∂V/∂t = ∇·(D ∇V) − I_ion(V, s) + I_stim,    I_stim = I_vol / (χ Cm),
/// with no-flux boundaries. A step of length Δt splits it (Godunov: R(Δt) then D(Δt); Strang:
/// R(Δt/2) D(Δt) R(Δt/2)) into the reaction R — every node's cell model, `reaction_dt` sub-steps
/// with the model's own scheme (Rush–Larsen for gates of ionic models) — and the diffusion D:
///   (M + θ Δt K) V⁺ = (M − (1 − θ) Δt K) V     (θ = 1 backward Euler, ½ Crank–Nicolson),
/// solved by the configured sparse solver warm-started from V (the matrix is assembled and
/// factorised once per Δt).
///
/// Units: scenes are SI (or quantities with units, base/units.h); inside, lengths are mm, times
/// ms, V mV, D mm²/ms, currents µA/µF (= mV/ms). Fields report V in mV and times in ms.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/row_state.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/geometry/region.h"
#include "gipsi/models/ep/cell_model.h"
#include "gipsi/models/fibres/rule_based_fibres.h"
#include "gipsi/numerics/adaptive_parallel.h"
#include "gipsi/numerics/sparse/linear_solver.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A train of rectangular pulses (times in ms): pulse k (0 ≤ k < count) is active on
/// [start + k·period, start + k·period + duration). Plain struct.
struct PulseTrain {
  double start = 0;     ///< ms
  double duration = 1;  ///< ms, > 0
  double period = 0;    ///< ms; 0 for a single pulse, else ≥ duration
  int count = 1;        ///< number of pulses (≥ 1)

  /// Total time [ms] during which a pulse is active within [t0, t1].
  [[nodiscard]] double ActiveTime(double t0, double t1) const;
  /// Whether a pulse is active at t [ms].
  [[nodiscard]] bool ActiveAt(double t) const;
};

/// A stimulus current into the nodes of a region. Plain struct.
struct StimulusSpec {
  std::string name;
  Region region;
  double amplitude = 0;  ///< applied current per capacitance [µA/µF = mV/ms], > 0 depolarises
  PulseTrain pulses;
};

/// Holds V at `voltage` in the nodes of a region while a pulse is active. Plain struct.
struct ClampSpec {
  std::string name;
  Region region;
  double voltage = 0;  ///< mV
  PulseTrain pulses;
};

enum class SplittingScheme { kGodunov, kStrang };

/// Parameters shared by every monodomain object. Plain struct with defaults.
struct EpTissueParams {
  std::shared_ptr<const CellModel> cell;  ///< required
  double sigma_longitudinal = 0;          ///< monodomain conductivity along fibres [S/m]
  double sigma_transverse = 0;            ///< across fibres [S/m]
  std::optional<Vec3> fibre;              ///< uniform fibre direction (needed if anisotropic)
  /// Per-element fibres from a rule instead (tet objects only).
  std::optional<TransmuralFibreRule> fibre_rule;
  double surface_to_volume = 1.4e5;  ///< χ [1/m] (1400 /cm)
  double capacitance = 0.01;         ///< Cm [F/m²] (1 µF/cm²)
  SplittingScheme splitting = SplittingScheme::kGodunov;
  double theta = 1.0;          ///< diffusion: 1 backward Euler, 0.5 Crank–Nicolson
  bool lumped_mass = true;     ///< else consistent mass
  double reaction_dt = 0;      ///< largest reaction sub-step [s]; 0: the object's step
  LinearSolverOptions linear;  ///< diffusion solver (default CG + Jacobi, 1e-8)
  /// The diffusion solver of a run split over MPI ranks (gipsi/parallel/), where it differs
  /// from `linear`: the object's "parallel" block (a Monodomain's only). Serial runs ignore it.
  std::optional<LinearSolverOptions> distributed_linear;
  std::vector<StimulusSpec> stimuli;
  std::vector<ClampSpec> clamps;
  double activation_threshold = 0;    ///< mV: activation when V rises through it
  double apd_repolarisation = 0.9;    ///< APD at this fraction of repolarisation
  std::vector<double> initial_state;  ///< per state variable; empty: the model's rest

  EpTissueParams() {
    linear.type = "cg";
    linear.preconditioner = "jacobi";
    linear.tolerance = 1e-8;
  }
  /// D = σ/(χ Cm) [mm²/ms] along (l) and across (t) the fibres.
  [[nodiscard]] double diffusivity_longitudinal() const;
  [[nodiscard]] double diffusivity_transverse() const;
  [[nodiscard]] bool anisotropic() const { return sigma_longitudinal != sigma_transverse; }
};

/// What a monodomain object carries from one step to the next, as a state value type
/// (gipsi/base/state_value.h): every cell's state variables and the activation/APD tracking.
/// The stimuli and clamps are functions of time, the cell models are immutable and the
/// diffusion solve starts from the current voltage. Copyable.
struct EpState {
  static constexpr const char* kTag = "EpState";
  static constexpr std::uint32_t kVersion = 1;

  CellStates cells;
  VecX activation_time;  ///< first activation [ms] per node, −1 where none
  VecX last_activation;  ///< latest activation [ms] per node, −1 where none
  VecX apd;              ///< last completed APD [ms] per node, −1 where none
  VecX v_min;            ///< lowest voltage since the last repolarisation [mV] (the APD's base)
  VecX v_peak;           ///< highest voltage since the last activation [mV]
  std::vector<unsigned char> depolarised;  ///< per node: activated and not yet repolarised
  int last_iterations = 0;                 ///< of the last diffusion solve

  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("cells", s.cells);
    v("activation_time", s.activation_time, Shape::kFixed);
    v("last_activation", s.last_activation, Shape::kFixed);
    v("apd", s.apd, Shape::kFixed);
    v("v_min", s.v_min, Shape::kFixed);
    v("v_peak", s.v_peak, Shape::kFixed);
    v("depolarised", s.depolarised, Shape::kFixed);
    v("last_iterations", s.last_iterations);
  }

  /// The state as one row per node, for a split monodomain's state moved to another partition
  /// (a checkpoint restored on another rank count, gipsi/parallel/). Node i's row holds its
  /// cell's state variables in the model's order, then activation_time, last_activation, apd,
  /// v_min, v_peak and depolarised (0 or 1): RowWidth values.
  [[nodiscard]] static int RowWidth(const CellModel& cell) { return cell.num_states() + 6; }
  /// A state of `num_nodes` cells of `cell` at rest, no activation: the shape to read into.
  [[nodiscard]] static EpState Sized(const CellModel& cell, std::size_t num_nodes);
  /// The rows of every node, node after node.
  [[nodiscard]] std::vector<double> ToRows() const;
  /// Sets every node from `rows` (num_nodes() rows of RowWidth; the state is sized already).
  void FromRows(std::span<const double> rows);
};

/// Base of the monodomain objects (see the file comment). Not copyable or movable.
class EpTissue : public SimObject, public RowState {
 public:
  /// RowState: EpState's rows per node (EpState::ToRows); shared: the last solve's iterations.
  /// The serial object and a split one's part write the same state, so either reads the
  /// other's (a checkpoint moved between runs on one process and on several).
  [[nodiscard]] StateRows ReadStateRows(StateReader& in, const ItemCounts& counts) const override;
  void WriteStateRows(StateWriter& out, const StateRows& rows) const override;
  [[nodiscard]] const EpTissueParams& params() const { return params_; }
  [[nodiscard]] const CellModel& cell() const { return *params_.cell; }
  [[nodiscard]] Index num_nodes() const { return static_cast<Index>(state_.cells.num_nodes()); }
  /// Transmembrane voltage [mV] of every node (a view of the cell states).
  [[nodiscard]] Eigen::Map<const VecX> voltage() const;
  /// First activation time [ms] per node, −1 where not activated yet.
  [[nodiscard]] const VecX& activation_time() const { return state_.activation_time; }
  /// Last completed APD [ms] per node, −1 where none.
  [[nodiscard]] const VecX& apd() const { return state_.apd; }
  /// ∫ V dΩ with the diffusion mass [mV·mm³] (conserved by diffusion alone).
  [[nodiscard]] double VoltageIntegral() const;
  /// Nodes driven by each stimulus / clamp (in declaration order).
  [[nodiscard]] const std::vector<std::vector<int>>& stimulus_nodes() const { return stim_nodes_; }
  [[nodiscard]] std::vector<ProfileEntry> ProfileBreakdown() const override;
  /// The state that evolves, bound with BindState (checkpoints and snapshots).
  [[nodiscard]] const EpState& state() const { return state_; }
  [[nodiscard]] std::string failure_detail() const override { return failure_detail_; }

 protected:
  EpTissue(std::string name, EpTissueParams params);

  /// How InitTissue sets a tissue up. Plain struct.
  struct TissueSetup {
    /// Refuse a stimulus or clamp region that selects no node of `domain()`. A distributed
    /// object's part of the mesh may hold none of a region's nodes; it checks the whole mesh.
    bool require_region_nodes = true;
    /// Create the serial diffusion solver from params().linear (a subclass that overrides
    /// SolveDiffusion with a solver of its own does not need it).
    bool serial_solver = true;
  };
  /// Call once from the subclass constructor after SetGeometry: sizes the cell states and
  /// selects the stimulus and clamp nodes on `domain()` (throws InputError for a region that
  /// selects nothing, unless `setup` says otherwise, and for bad solver options).
  void InitTissue(TissueSetup setup);
  void InitTissue() { InitTissue(TissueSetup{}); }
  /// Sets the diffusion operator (internal units, see the file comment). `stiffness` is
  /// symmetric with both triangles stored and rows summing to zero; `mass` is the lumped mass
  /// per node [mm³] and `consistent_mass`, if the parameters ask for it, has K's pattern.
  void SetDiffusionOperator(SparseMatrix stiffness, VecX lumped_mass,
                            SparseMatrix consistent_mass = {});
  /// Node positions in mm (for diagnostics).
  [[nodiscard]] virtual Vec3 NodePositionMm(Index node) const;

  StepStatus DoStep(double t, double dt) override;
  /// One diffusion solve (M + θΔt K) V⁺ = (M − (1 − θ)Δt K) V of length `dt_ms`, in place on
  /// the num_nodes() voltages `v`; sets `iterations` (the solver's) and, on failure, `detail`
  /// (what the solver reached, for failure_detail()). The default assembles and factorises the
  /// system from SetDiffusionOperator's matrices whenever Δt changes and solves with
  /// params().linear; a distributed object solves its global system instead.
  virtual StepStatus SolveDiffusion(double dt_ms, double* v, int& iterations, std::string& detail);
  /// The diffusion factorisation depends on the step size only: a snapshot restore keeps it; a
  /// checkpoint holds none, so its restore refactorises at the next step (the same factors).
  void RestoreStateCache(StateReader& /*in*/) override { system_dt_ = -1; }
  void StateRestored() override;
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  [[nodiscard]] const double* DoFieldMemory(FieldId id) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;

  EpTissueParams params_;

 private:
  void ReactionSteps(double t0_ms, double length_ms);
  [[nodiscard]] bool FillStimulus(double t0, double t1);
  void ApplyClamps(double t);
  [[nodiscard]] StepStatus Diffuse(double dt_ms);
  void TrackActivation(double t0_ms, double dt_ms);
  [[nodiscard]] StepStatus CheckVoltage();
  [[nodiscard]] double* v_data() { return state_.cells.var(params_.cell->v_index()); }

  EpState state_;
  std::vector<FieldId> state_fields_;  // one per cell state (V included)
  FieldId f_activation_, f_last_activation_, f_apd_, f_activated_, f_integral_, f_cg_;
  std::vector<std::vector<int>> stim_nodes_, clamp_nodes_;
  VecX i_stim_;
  std::vector<int> stimulated_;  // nodes with a non-zero i_stim_ entry

  // Diffusion.
  SparseMatrix stiffness_, consistent_mass_, system_;
  VecX lumped_mass_, rhs_, solution_, work_;
  std::unique_ptr<LinearSolver> solver_;
  double system_dt_ = -1;  // Δt [ms] of system_

  // Activation and APD.
  VecX v_prev_;  // V at the start of the step (a copy of the state's)

  struct Profile {
    double reaction = 0, diffusion = 0, tracking = 0;
    std::int64_t cg_iterations = 0, steps = 0;
  } profile_;
  // The cell-model and tracking loops run on the team or serially, whichever has been faster
  // lately (a busy neighbour makes a two-thread region wait for a time slice).
  AdaptiveParallel reaction_parallel_, tracking_parallel_;
  std::string failure_detail_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
