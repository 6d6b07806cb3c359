#pragma once
/// @file
/// `SimObject`: one physical process (or an aggregate of processes) with its three geometries,
/// named fields, boundary conditions and a `Step`. The GiPSi simulation API.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/base/object_state.h"
#include "gipsi/base/state_binding.h"
#include "gipsi/base/state_value.h"
#include "gipsi/base/stop_token.h"
#include "gipsi/core/boundary_conditions.h"
#include "gipsi/core/cavity_law.h"
#include "gipsi/core/field.h"
#include "gipsi/core/object_path.h"
#include "gipsi/core/step_status.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/mapping.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// What an object is drawn with: a triangle surface whose vertices follow the domain through a
/// mapping (barycentric embedding of a finer or coarser surface), or the boundary itself.
/// Copyable and movable.
struct DisplayGeometry {
  Triangles triangles = Triangles(3, 0);  ///< 3 by T, in display-vertex numbering
  /// Maps current domain positions to display vertices; when empty, the display geometry is
  /// the boundary surface (vertices gathered from the domain).
  std::optional<PointMap> map;
  Points positions = Points(3, 0);  ///< 3 by V current display vertex positions
};

/// Ids of the fields every deformable (mechanical) object declares under the same names, units
/// and meanings, so connectors, collision response and probes can rely on them: "position",
/// "velocity", "external_force" (node, read/write), "displacement" (node, read),
/// "boundary_position", "boundary_velocity", "boundary_displacement", "reaction_force"
/// (boundary vertex, read). Plain struct.
struct MechanicalFieldIds {
  FieldId position, velocity, displacement, external_force;
  FieldId boundary_position, boundary_velocity, boundary_displacement, reaction_force;
};

/// Base class of every simulation object. Not copyable or movable (others hold references).
///
/// Subclasses: declare their fields in the constructor (`DeclareField`), set their geometries
/// (`SetGeometry`), and implement `DoStep`, `DoReadField`, `DoWriteField` and
/// `domain_positions()`. The public methods check their arguments and call those hooks.
class SimObject {
 public:
  SimObject(const SimObject&) = delete;
  SimObject& operator=(const SimObject&) = delete;
  virtual ~SimObject() = default;

  /// The object's own name: its key in the scene or in its aggregate's "parts" ("muscle").
  /// Lookups (orders, connectors, FindPart) use it.
  [[nodiscard]] const std::string& name() const { return name_; }
  /// The name messages give: the path from the scene's top level ("heart.muscle" for a part
  /// of the aggregate "heart"), the name the command line and the viewer accept. Set at
  /// construction from the enclosing ObjectPathScope; equal to name() at the top level.
  [[nodiscard]] const std::string& path() const { return path_; }
  /// The registered type name, e.g. "MassSpring".
  [[nodiscard]] virtual std::string_view type_name() const = 0;

  // --- Geometries ---
  /// Reference (rest) domain geometry. Objects without a mesh have an empty Mesh.
  [[nodiscard]] const Mesh& domain() const { return *domain_; }
  [[nodiscard]] const std::shared_ptr<const Mesh>& domain_ptr() const { return domain_; }
  /// Current positions of the domain nodes, 3 by domain().num_nodes().
  [[nodiscard]] virtual const Points& domain_positions() const = 0;
  /// Boundary geometry (triangles and the domain node of each boundary vertex).
  [[nodiscard]] const BoundarySurface& boundary() const { return boundary_; }
  [[nodiscard]] const DisplayGeometry& display() const { return display_; }
  /// Recomputes display().positions from the current domain positions (a cache derived from the
  /// state, hence const). Allocation-free.
  void UpdateDisplay() const;
  /// Replaces the display geometry by `triangles` on `rest_vertices` (3 by V), embedded in the
  /// domain barycentrically (tet domains) or by closest point (surface domains). Throws
  /// InputError if a vertex lies farther than `max_distance` from the domain.
  void EmbedDisplay(const Points& rest_vertices, const Triangles& triangles, double max_distance);
  /// Interpolation of node values at points of the rest domain (probes at points, volume
  /// connectors, display embedding): by default barycentric in the domain's tets, or on its
  /// triangles for surface domains; objects on other geometries (e.g. a structured grid)
  /// override it. Throws InputError as the PointMap builders do.
  [[nodiscard]] virtual PointMap MapFromNodes(const Points& targets) const;
  /// The node pairs the object is drawn with as lines when it has its own (a spring network's
  /// springs), 2 by S; empty (the default) to draw the domain's edges. An object with segments
  /// and no display surface is drawn as lines by default.
  [[nodiscard]] virtual Eigen::Matrix2Xi DisplaySegments() const { return Eigen::Matrix2Xi(2, 0); }

  // --- Boundary conditions ---
  [[nodiscard]] BoundaryConditions& boundary_conditions() { return bcs_; }
  [[nodiscard]] const BoundaryConditions& boundary_conditions() const { return bcs_; }

  // --- Fields (Get/Set) ---
  [[nodiscard]] std::span<const FieldInfo> fields() const { return fields_; }
  /// The field called `name`, or std::nullopt.
  [[nodiscard]] std::optional<FieldId> TryFindField(std::string_view name) const;
  /// The field called `name`; throws InputError naming the object and listing its fields.
  [[nodiscard]] FieldId FindField(std::string_view name) const;
  [[nodiscard]] const FieldInfo& field_info(FieldId id) const;
  /// Number of items of a field (nodes, elements, boundary vertices/faces, or 1).
  [[nodiscard]] Index FieldCount(FieldId id) const;
  /// Copies the field into `out` (components by count). Preconditions (checked, abort): the
  /// field is readable and `out` has the right shape. Allocates nothing.
  void ReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const;
  /// Copies the listed items of a node, element or boundary field (indices in [0, count),
  /// repeats allowed) into `out` (components by items.size()): what ReadField gives in those
  /// columns, bitwise. Probes read through it, so an object whose fields are not all in one
  /// process (a distributed object's view, gipsi/parallel/) sends only the items asked for.
  /// Preconditions as ReadField (checked, abort), and a field with items. Collective where
  /// ReadField is.
  void ReadFieldItems(FieldId id, std::span<const int> items,
                      Eigen::Ref<Eigen::MatrixXd> out) const;
  /// Sets the field from `in` (components by count). Preconditions as ReadField, for writing.
  void WriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in);
  /// Where a readable field's values are stored, if they are rather than computed on request:
  /// components × count doubles, column-major (ReadField's layout), equal to what ReadField
  /// gives. The address holds while the object lives (steps, retries and checkpoint restores
  /// copy into it), so a view of it (the Python module's) follows the simulation without a
  /// copy. nullptr for a computed field. Read-only: writes go through WriteField.
  [[nodiscard]] const double* FieldMemory(FieldId id) const;

  // --- Simulation ---
  /// Advances by `dt` > 0 from time(). Never throws; reports trouble in the status.
  StepStatus Step(double dt);
  /// Simulated time of this object [s].
  [[nodiscard]] double time() const { return time_; }
  /// Sets the object's clock (the kernel re-synchronises it to the exact macro-step time after
  /// sub-stepping, so round-off does not accumulate; checkpoints restore it).
  void SetTime(double t) { time_ = t; }
  /// Number of successful steps taken.
  [[nodiscard]] std::int64_t step_count() const { return step_count_; }
  /// What a VTU series writes of this object in this process. Plain struct.
  struct OutputPiece {
    const SimObject* object = nullptr;  ///< whose domain and node/element fields are written
    int index = 0;                      ///< this process's piece
    int count = 1;                      ///< pieces in all (more than one: a `.pvtu` indexes them)
  };
  /// The object itself, whole; a distributed object (gipsi/parallel/) gives this rank's part as
  /// one piece of as many as there are ranks: each rank writes its piece and the first rank
  /// the `.pvtu` that joins them (io/outputs.h).
  [[nodiscard]] virtual OutputPiece output_piece() const { return {this, 0, 1}; }
  /// Output on quadratic (10-node) tets, for objects whose domain is elevated to them
  /// (MixedSolid): the current positions of the edge nodes, numbered after the domain's nodes;
  /// the two domain nodes at the ends of each; and the 10-node tets (the domain's tets in order:
  /// vertices, then the middle nodes of the edges (0,1), (1,2), (0,2), (0,3), (1,3), (2,3)).
  /// Plain struct.
  struct QuadraticOutput {
    Points edge_positions = Points(3, 0);
    Eigen::Matrix2Xi edge_ends = Eigen::Matrix2Xi(2, 0);
    Eigen::Matrix<int, 10, Eigen::Dynamic> tets = Eigen::Matrix<int, 10, Eigen::Dynamic>(10, 0);
  };
  /// Fills `out` and returns true if the object has quadratic output; VTU series then write
  /// quadratic cells. Default: false.
  [[nodiscard]] virtual bool GetQuadraticOutput(QuadraticOutput& /*out*/) const { return false; }
  /// Node field `id` at the edge nodes (components by edges): true if the object computes it
  /// there (a quadratic field such as displacement); false leaves the writer the mean of the
  /// edge's ends (exact for fields linear on each tet). Default: false.
  [[nodiscard]] virtual bool ReadEdgeNodeField(FieldId /*id*/,
                                               Eigen::Ref<Eigen::MatrixXd> /*out*/) const {
    return false;
  }
  /// Node field `id` at points: `at` (components by points) holds the blend Σ_k weights(k, j) ·
  /// value(nodes(k, j)) of the node values (MapFromNodes' layout, node ids). An object whose
  /// node fields are of higher order than its domain mesh adds what the blend misses
  /// (MixedSolid: the P2 displacement's bow inside each tet), so probes at points read the
  /// object's own interpolation. Default: nothing (the blend is the object's interpolation).
  virtual void CorrectInterpolated(FieldId /*id*/, const Eigen::Matrix4Xi& /*nodes*/,
                                   const Eigen::Matrix4Xd& /*weights*/,
                                   Eigen::Ref<Eigen::MatrixXd> /*at*/) const {}
  /// Leaf objects for output (an aggregate returns its parts; a plain object returns itself).
  virtual void CollectLeaves(std::vector<const SimObject*>& out) const { out.push_back(this); }
  /// A part of an aggregate by (possibly dotted) name; plain objects have none (nullptr).
  [[nodiscard]] virtual SimObject* FindPart(std::string_view /*name*/) const { return nullptr; }
  /// After a failed step, extra context for the diagnostic (an aggregate names the failing
  /// part); empty by default.
  [[nodiscard]] virtual std::string failure_detail() const { return {}; }
  /// Where the object's step time went, for `gipsi run --profile`: named figures such as
  /// {"assembly", 1.2, "s"} or {"Newton iterations", 340, ""}. Empty by default.
  struct ProfileEntry {
    std::string name;
    double value = 0;
    std::string unit;
  };
  [[nodiscard]] virtual std::vector<ProfileEntry> ProfileBreakdown() const { return {}; }
  /// Checkpoints (gipsi/base/state.h): writes the clock, step count and applied boundary
  /// conditions (not the coupling loads, which the next macro step clears), then the type's own
  /// state (SaveObjectState). RestoreState reads it back; the object then continues bitwise
  /// identically. Throw InputError for state from another scene or object type.
  void SaveState(StateWriter& out) const;
  void RestoreState(StateReader& in);
  /// What SaveState wrote around the type's state, read without the object: a checkpoint of
  /// another partition's part of a split object (gipsi/parallel/). Plain struct.
  struct SavedHeader {
    std::string name, type;
    double time = 0;
    std::int64_t steps = 0;
  };
  /// Reads what SaveState wrote for an object whose boundary had `boundary_vertices` vertices
  /// and `boundary_faces` faces: the header, the applied boundary conditions (dropped: they
  /// are on that boundary) and, through `read_own`, the type's state.
  static SavedHeader ReadSavedState(StateReader& in, Index boundary_vertices, Index boundary_faces,
                                    const std::function<void(StateReader&)>& read_own);
  /// RestoreState of what SaveState would write with clock `time`, `steps`, this object's
  /// applied boundary conditions and the type's state written by `write_own` (a split object's
  /// part restored from another partition's checkpoint, in this part's layout).
  void RestoreStateFrom(double time, std::int64_t steps,
                        const std::function<void(StateWriter&)>& write_own);
  /// Everything of the subclass that influences the future (state, integrator history, event
  /// logs), and the solver caches a bitwise continuation needs (a kept factorisation). The
  /// defaults write and read the state bound by BindState, and throw InputError("object type X
  /// does not support checkpoints") for a type that bound none.
  virtual void SaveObjectState(StateWriter& out) const;
  virtual void RestoreObjectState(StateReader& in);
  /// Checkpoints: reads the applied boundary conditions SaveState wrote into
  /// boundary_conditions() (the default). A split object's part-only view overrides it to
  /// place them once it knows whose they are (a part's, the whole boundary's).
  virtual void RestoreAppliedConditions(StateReader& in);

  /// Whether snapshots copy the type's state as a value (it bound one with BindState) rather
  /// than serialising it through SaveObjectState (`gipsi validate` lists the objects that
  /// serialise: their retries cost more).
  [[nodiscard]] virtual bool state_is_value() const { return state_binding_ != nullptr; }
  /// Snapshots (gipsi/base/object_state.h), the kernel's step retry: a new box holding the
  /// object's current state (clock, step count, applied boundary conditions, the type's state).
  [[nodiscard]] std::unique_ptr<ObjectState> NewSnapshot() const;
  /// Copies the current state into `into`, a box from this object's NewSnapshot. For a type
  /// with a state value type this is a copy of values, allocation-free when shapes agree; the
  /// boundary conditions are copied only if they changed.
  void TakeSnapshot(ObjectState& into) const;
  /// Returns to the state in `from` (from this object's NewSnapshot). Stepping on from there
  /// gives the same bits every time; solver caches are rebuilt or dropped by the type's rule
  /// (docs/architecture.md, "State"), so the result may differ from the first time the state
  /// was stepped from only where that rule says.
  void RestoreSnapshot(const ObjectState& from);
  /// Called by the kernel at the start of every macro step (aggregates forward it).
  virtual void BeginMacroStep() { bcs_.ClearCouplingLoads(); }
  /// The run's stop request (the kernel hands it down when it is initialised; aggregates pass
  /// it to their parts). An object whose step can run long (Newton iterations, load steps)
  /// polls `stop_token()` inside it and, when a stop is requested, restores the state of the
  /// start of the step and returns StepStatus::Stopped. Default: a token that never stops.
  void SetStopToken(StopToken token) {
    stop_token_ = token;
    DoSetStopToken(token);
  }
  [[nodiscard]] const StopToken& stop_token() const { return stop_token_; }

 protected:
  explicit SimObject(std::string name);

  /// Sets the domain and boundary geometries and sizes the boundary conditions. The display
  /// geometry defaults to the boundary surface.
  void SetGeometry(std::shared_ptr<const Mesh> domain, BoundarySurface boundary);
  /// Replaces the display geometry by `triangles` on vertices that `map` interpolates from the
  /// domain nodes (`rest_positions` their rest positions): a default display other than the
  /// boundary (MixedSolid's curved faces). EmbedDisplay may still replace it.
  void SetDisplayGeometry(Triangles triangles, PointMap map, Points rest_positions);
  /// Called by UpdateDisplay after the display positions were interpolated from the domain
  /// positions: objects whose geometry is of higher order than the domain mesh add what that
  /// interpolation misses (MixedSolid: the bow of its curved edges). Default: nothing.
  virtual void CorrectDisplayPositions(DisplayGeometry& /*display*/) const {}
  /// Called when the display geometry changes (SetDisplayGeometry, EmbedDisplay), for objects
  /// that keep tables of it. Default: nothing.
  virtual void OnDisplayChanged() {}
  /// Declares a field; returns its id. Call from the constructor only.
  FieldId DeclareField(FieldInfo info);
  /// Declares the mechanical fields (MechanicalFieldIds). Call from the constructor only.
  MechanicalFieldIds DeclareMechanicalFields();
  /// Fills `out` (3 by boundary vertices) if `id` is one of the boundary kinematic fields of
  /// `ids`, from node positions (3 by N) and node-major velocities (3N); returns whether it did.
  bool ReadBoundaryKinematics(const MechanicalFieldIds& ids, FieldId id, const Points& positions,
                              const double* velocities, Eigen::Ref<Eigen::MatrixXd> out) const;

  virtual StepStatus DoStep(double t, double dt) = 0;

  /// Declares the object's state value type (gipsi/base/state_value.h): `state`, a member whose
  /// static `Fields` lists everything that evolves, is then what checkpoints save and restore
  /// (WriteFields / ReadFields) and what step retries copy (a StateBox<S>), with no further
  /// hook to write. Call once, from the constructor. After a restore, StateRestored() rebuilds
  /// what derives from the state. A checkpoint read fails as a whole: the state is replaced only
  /// once every field was read. If `S` declares `static constexpr std::string_view kTag` and
  /// `std::uint32_t kVersion`, checkpoints wrap its fields in a section of that tag and version
  /// (raise the version when the fields change, and an old checkpoint is refused by name). A
  /// solver cache that a bitwise continuation needs (a kept factorisation) goes beside it
  /// through the three cache hooks below.
  template <class S>
  void BindState(S& state) {
    GIPSI_CHECK(state_binding_ == nullptr, "object '{}': BindState called twice", name_);
    state_binding_ = BindStateValue(state);
  }
  /// Declares a state value type `S` whose live values are kept in several members (a device,
  /// a tick, a safety stage): `get(S&)` copies them into a value, `set(const S&)` copies one
  /// back, validating it first (throw InputError, changing nothing). Checkpoints and snapshots
  /// then hold an `S`, as with BindState (gipsi/base/state_binding.h). Call once, from the
  /// constructor, instead of BindState.
  template <class S, class Get, class Set>
  void BindGatheredState(Get get, Set set) {
    GIPSI_CHECK(state_binding_ == nullptr, "object '{}': BindState called twice", name_);
    state_binding_ = BindGatheredStateValue<S>(std::move(get), std::move(set));
  }
  /// Called after the state bound by BindState was replaced (a checkpoint or a snapshot
  /// restored): rebuild what derives from it. Default: nothing.
  virtual void StateRestored() {}
  /// Caches of the future that are not state but change the bits of what follows (a Newton
  /// solver's warm start and kept factorisation), for a bound state (docs/architecture.md,
  /// "State"): checkpoints write them after the state (SaveStateCache) and read them back
  /// before the state is replaced (RestoreStateCache; a throw leaves the object untouched, so
  /// read into temporaries or validate first); a snapshot restore drops them instead
  /// (DropStateCache: the retry of a failed step recomputes them). Defaults: nothing.
  virtual void SaveStateCache(StateWriter& /*out*/) const {}
  virtual void RestoreStateCache(StateReader& /*in*/) {}
  virtual void DropStateCache() {}

  /// Hooks of the snapshots: a box for the type's state, copying into it, and restoring from
  /// it (then rebuilding what derives from the state). The defaults copy the state bound by
  /// BindState, else serialise through SaveObjectState / RestoreObjectState into a ByteState;
  /// a type with its own state value type `S` returns a StateBox<S> and copies values.
  [[nodiscard]] virtual std::unique_ptr<ObjectState> NewObjectState() const;
  virtual void CopyObjectState(ObjectState& into) const;
  virtual void SetObjectState(const ObjectState& from);
  /// Hook of SetStopToken (an aggregate forwards the token to its parts). Default: nothing.
  virtual void DoSetStopToken(StopToken /*token*/) {}
  virtual void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const = 0;
  /// Hook of ReadFieldItems (items checked). Default: the columns of FieldMemory, else of a
  /// ReadField into a buffer.
  virtual void DoReadFieldItems(FieldId id, std::span<const int> items,
                                Eigen::Ref<Eigen::MatrixXd> out) const;
  /// Hook of FieldMemory (readable fields only); default nullptr: every field computed.
  [[nodiscard]] virtual const double* DoFieldMemory(FieldId /*id*/) const { return nullptr; }
  virtual void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) = 0;

 private:
  // RestoreState of a split object's part (a distributed run's checkpoint) into this serial
  // object: every rank's part, from the files of CheckpointPieces (core/row_state.h), with
  // `conditions` the applied boundary conditions of the first file's SimObject section (a
  // part's, the whole boundary's, or none).
  void RestoreFromPieces(StateReader& in, BoundaryConditions::Applied conditions);
  // Restores `read` (conditions of any size, from a distributed run's checkpoint) into
  // boundary_conditions(): nothing if `read` is empty (a part-only view without a store).
  void RestoreReadConditions(StateReader& in, BoundaryConditions::Applied read);

  std::string name_;
  std::string path_;  // name_ under the ObjectPathScope active at construction
  std::unique_ptr<StateBinding> state_binding_;
  std::shared_ptr<const Mesh> domain_;
  BoundarySurface boundary_;
  mutable DisplayGeometry display_;  // positions are a cache of the state
  BoundaryConditions bcs_;
  std::vector<FieldInfo> fields_;
  double time_ = 0;
  std::int64_t step_count_ = 0;
  StopToken stop_token_;
};

/// Number of domain elements: tets if the domain has any, else triangles.
Index NumDomainElements(const Mesh& mesh);

}  // namespace gipsi
GIPSI_EXPORT_END
