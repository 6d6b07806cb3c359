#pragma once
/// @file
/// `WholeDomainView`: a distributed object's part (one rank's share of the mesh, e.g. a
/// DistributedMonodomain) presented as one object on the whole mesh, so that everything built
/// for serial objects (connectors, probes, VTU series, the kernel's retries) runs unchanged on
/// every rank of a distributed scene run. The view's domain is the whole mesh; reading a node
/// or element field gathers every rank's owned values into the whole mesh's order on every
/// rank (MPI_Allgatherv: collective, and O(whole mesh) per rank per read), writing one keeps
/// this rank's entries; global fields are the part's (its own reductions). Boundary fields are
/// offered once the part's boundary is mapped to the whole mesh's (ForwardBoundaryConditions),
/// a shared boundary vertex's value read from its node's owner. Steps, stop requests, profiles and
/// failure details go to the part; the part's state is the view's. Step retries take the part's own
/// snapshots (no communication). A checkpoint holds this rank's part after the rank count, the rank
/// and a fingerprint of the partition (every rank writes its own file, docs/scale-out.md); a
/// restore checks them on every rank together and, once read, that every rank's part is at the same
/// time and step, so a checkpoint restores bitwise on the rank count and partition that wrote it,
/// and a set of files from different checkpoints (a run stopped while writing them) is refused.
/// On another rank count a part whose state is rows per item (RowState: per node, tet and
/// boundary face) is restored from every file's part: each rank reads some of the files (rank
/// q those of ranks q, q + M, ...), and the rows of the owned nodes, the tets and the faces move
/// to the new parts (MoveRows); the run then goes on within the solvers' tolerance of the
/// uninterrupted one (another cut sums in another order; solver caches start afresh).
///
/// Without the whole mesh (the second constructor: a "part-only" view, for an object nothing
/// but probes, outputs and connectors coupling its parts reads, ObjectBuildContext::in_blocks)
/// the view's domain and boundary
/// are the part's, its fields are the part's local ones, and probes address the whole mesh's
/// nodes through its PartitionedObject calls (collective; the whole mesh's indices are the
/// part's `whole_node`). No rank then holds anything of the size of the whole mesh: when the
/// part takes conditions (a FemSolid's), the view's store holds its part's boundary's only
/// (selected with SelectConditionItems, forwarded as the other view does; checkpoints move them
/// by rows with the state).
///
/// Every rank must make the same calls in the same order (they do when every rank runs the
/// same kernel on the same scene). The whole-field gathers make ReadField the simple path, not
/// the scalable one: VTU series write the part as one piece per rank instead (output_piece),
/// and probes read only the items they need (ReadFieldItems), each sent by the rank that owns
/// it. A connector between two objects split alike (SplitAlike) reads and writes their parts
/// (local_part) and refreshes shared nodes from their owners (ShareOwnedNodeValues, through a
/// ghosted PETSc Vec); other connectors read whole fields (docs/scale-out.md).

#include <mpi.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/state.h"
#include "gipsi/core/cavity_law.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/core/row_state.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/parallel/mesh_partition.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable or movable (a SimObject). A CavityWall when its part is one (a FemSolid with
/// cavities): the calls go to the part.
class WholeDomainView final : public SimObject, public CavityWall, public PartitionedObject {
 public:
  /// Where the part's boundary lies on the whole mesh's (MakeBoundary): the whole boundary
  /// vertex of each part boundary vertex, the whole face of each part face. Plain struct.
  struct BoundaryMap {
    std::vector<int> vertex, face;
    /// The whole boundary's vertex and face counts (a part-only view's checkpoints hold them;
    /// the other view reads them from its whole mesh).
    std::int64_t whole_vertices = 0, whole_faces = 0;
  };
  /// `part` is this rank's object on `mesh_part.mesh` (`mesh_part` must outlive the view: the
  /// part usually owns it), `whole` the mesh it was cut from. Collective. With `boundary`,
  /// before each step the view's boundary conditions (on the whole mesh's boundary, where
  /// scenes, events and connectors write them) are copied to the part's, part vertex v taking
  /// whole vertex boundary.vertex[v]'s constraints and loads, part face f whole face
  /// boundary.face[f]'s (the part counts a nodal force on the node's owner only), and the
  /// part's boundary fields are the view's.
  WholeDomainView(std::unique_ptr<SimObject> part, const MeshPart& mesh_part,
                  std::shared_ptr<const Mesh> whole, MPI_Comm comm,
                  std::optional<BoundaryMap> boundary = std::nullopt);
  /// A part-only view (see the file comment): `part` on `mesh_part.mesh` (which must outlive
  /// the view), no whole mesh on any rank. Collective. With `boundary` (its whole counts set),
  /// the view keeps a store of boundary conditions on its part's boundary (the part's order):
  /// conditions are selected with SelectConditionItems and copied to the part before each
  /// step, and checkpoints hold them with the whole boundary's numbers of the part's items (so
  /// they move between rank counts and serial runs, as the state does).
  WholeDomainView(std::unique_ptr<SimObject> part, const MeshPart& mesh_part, MPI_Comm comm,
                  std::optional<BoundaryMap> boundary = std::nullopt);
  ~WholeDomainView() override;

  /// PartitionedObject: false for a part-only view. The calls below work in both kinds.
  [[nodiscard]] bool holds_whole_domain() const override { return !part_only_; }
  [[nodiscard]] double WholeDiagonal() const override { return whole_diagonal_; }
  [[nodiscard]] std::int64_t whole_num_nodes() const override {
    return mesh_part_.num_global_nodes;
  }
  [[nodiscard]] std::int64_t whole_num_tets() const override { return mesh_part_.num_global_tets; }
  [[nodiscard]] PointMap LocateWhole(const Points& targets) const override;
  [[nodiscard]] std::vector<int> SelectWholeNodes(const Region& region) const override;
  void ReadWholeNodes(FieldId id, std::span<const int> nodes,
                      Eigen::Ref<Eigen::MatrixXd> out) const override;
  [[nodiscard]] std::vector<int> SelectOwnedNodes(const Region& region) const override;
  void ReadOwnedNodes(FieldId id, std::span<const int> local,
                      Eigen::Ref<Eigen::MatrixXd> out) const override;
  void CombineAcross(std::span<double> values, Combine how) const override;
  [[nodiscard]] std::vector<int> SelectOwnedBoundaryVertices(const Region& region) const override;
  [[nodiscard]] ConditionItems SelectConditionItems(const Region& region,
                                                    bool faces) const override;
  [[nodiscard]] SimObject& local_part() override { return *part_; }
  [[nodiscard]] const SimObject& local_part() const override { return *part_; }
  [[nodiscard]] Index num_owned_nodes() const override { return mesh_part_.num_owned; }
  [[nodiscard]] std::span<const int> whole_nodes_of_part() const override {
    return mesh_part_.whole_node;
  }
  [[nodiscard]] std::span<const int> whole_tets_of_part() const override {
    return mesh_part_.whole_tet;
  }
  void ShareOwnedNodeValues(Eigen::Ref<Eigen::MatrixXd> values) const override;
  /// The part's node fields at each rank's points (parallel/parts_interpolation.h), for either
  /// kind of view: only the parts are read.
  [[nodiscard]] std::unique_ptr<PartsInterpolation> InterpolateAtPoints(
      const Points& points) const override;
  /// The nearest item's value at each rank's points: the candidates are the part's owned nodes,
  /// its tets, or (part-only view) its owned boundary vertices or its boundary faces.
  [[nodiscard]] std::unique_ptr<PartsInterpolation> NearestAtPoints(
      FieldLocation location, const Points& points) const override;
  /// A part-only view's boundary-vertex fields at each rank's points, on the parts' boundary
  /// faces, and the transpose (BoundaryInterpolation); InputError on the other view.
  [[nodiscard]] std::unique_ptr<BoundaryInterpolation> InterpolateOnBoundary(
      const Points& points) const override;
  [[nodiscard]] int process() const override { return mesh_part_.rank; }
  [[nodiscard]] int num_processes() const override { return mesh_part_.size; }
  /// How many node or element fields this view has gathered whole (ReadField: an Allgatherv of
  /// the whole field to every rank), so tests can check that a coupling does not.
  [[nodiscard]] std::int64_t whole_field_reads() const { return whole_field_reads_; }

  [[nodiscard]] std::string_view type_name() const override { return part_->type_name(); }
  [[nodiscard]] const Points& domain_positions() const override { return domain().nodes; }
  [[nodiscard]] std::string failure_detail() const override { return part_->failure_detail(); }
  [[nodiscard]] std::vector<ProfileEntry> ProfileBreakdown() const override {
    return part_->ProfileBreakdown();
  }
  void SaveObjectState(StateWriter& out) const override;
  /// Collective: every rank restores its own rank's file; on another rank count (a part that is
  /// a RowState, with SetCheckpointFiles) rank q reads rank q % N's file of N. A checkpoint of a
  /// run on one process (the serial object's state, every rank reading the one file) restores
  /// as a part of one rank's checkpoint would: rank 0 reads the rows and they move to the parts.
  void RestoreObjectState(StateReader& in) override;
  /// A part-only view reads the conditions of any size and places them in RestoreObjectState,
  /// once the part's section says whose they are (its part's, another rank's part's, the whole
  /// boundary's): a store of its part's takes its own, moved rows (another rank count) or its
  /// rows of the whole boundary's; a view without a store (no BoundaryMap) takes them only if
  /// they apply nothing (nothing names a part-only object, so nothing set any).
  void RestoreAppliedConditions(StateReader& in) override;
  /// The files of the distributed checkpoint being resumed, rank 0's first (the tool sets them
  /// before Kernel::ReadCheckpoint): a restore on another rank count reads the parts in them.
  /// Empty (the default): a restore accepts only the rank count that wrote the checkpoint.
  static void SetCheckpointFiles(std::vector<std::filesystem::path> files);
  [[nodiscard]] std::unique_ptr<ObjectState> NewObjectState() const override {
    return part_->NewSnapshot();
  }
  void CopyObjectState(ObjectState& into) const override { part_->TakeSnapshot(into); }
  void SetObjectState(const ObjectState& from) override { part_->RestoreSnapshot(from); }
  void BeginMacroStep() override;
  /// VTU series write the part, one piece per rank.
  [[nodiscard]] OutputPiece output_piece() const override {
    return {part_.get(), mesh_part_.rank, mesh_part_.size};
  }
  [[nodiscard]] const SimObject& part() const { return *part_; }
  /// The part's cavities (none if it is not a CavityWall).
  [[nodiscard]] std::vector<std::string> cavity_names() const override;
  /// The part's; throws InputError if it is not a CavityWall.
  void AttachCavityLaw(std::string_view cavity, CavityLaw* law) override;

 protected:
  StepStatus DoStep(double t, double dt) override;
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  /// Each rank sends the asked items it owns, to every rank (MPI_Allgatherv of O(items)):
  /// how probes read the part.
  void DoReadFieldItems(FieldId id, std::span<const int> items,
                        Eigen::Ref<Eigen::MatrixXd> out) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;
  void DoSetStopToken(StopToken token) override { part_->SetStopToken(token); }

 private:
  // How the owned items of every rank line up in an Allgatherv, and where they go.
  struct Layout {
    std::vector<int> counts, offsets;  // items per rank and where each rank's start
    std::vector<int> whole;            // the whole-mesh index of every gathered item
    int owned = 0;                     // this rank's items: the local ones [0, owned)
    std::vector<int> owned_local;      // per whole-mesh item: its local index if owned, else -1
  };
  static Layout MakeLayout(const std::vector<int>& whole_of_local, std::int64_t owned,
                           MPI_Comm comm);

  // The layouts of the part's boundary items, and its boundary fields declared (BoundaryMap).
  void MapBoundary(BoundaryMap map);
  // Copies the view's boundary conditions to the part's (BoundaryMap).
  void CopyBoundaryConditions();
  // The whole boundary's faces where the view forwards conditions, else 0.
  [[nodiscard]] std::int64_t whole_boundary_faces() const {
    return forward_bcs_ ? whole_faces_ : 0;
  }
  // What the view's SimObject section holds as its applied conditions.
  [[nodiscard]] SavedConditions saved_conditions() const;
  // A part-only view's restore of the conditions RestoreAppliedConditions read, on the rank
  // count and partition that wrote them or from the whole boundary's (a view with the whole
  // mesh, a serial object: `kept` kWhole); "" or why they do not fit. Not collective.
  [[nodiscard]] std::string PlaceReadConditions(SavedConditions kept);
  // On another rank count: the parts' conditions (`vertex_of`, `face_of`: the whole boundary's
  // items of the rows) moved to the parts that hold their items (MoveRows). Collective.
  void MoveConditions(StateReader& in, const std::vector<int>& vertex_of,
                      std::vector<double>& vertex_rows, const std::vector<int>& face_of,
                      std::vector<double>& face_rows);
  // The local nodes (owned and shared) of the whole domain's selection: group regions gathered
  // (a triangle or tet group names a node only where its triangle or tet is), node ids mapped,
  // other regions decided where the nodes are. Collective for groups and node ids.
  [[nodiscard]] std::vector<int> SelectLocalNodes(const Region& region) const;

  std::unique_ptr<SimObject> part_;
  const MeshPart& mesh_part_;
  std::vector<int> bc_vertex_, bc_face_;  // BoundaryMap
  bool forward_bcs_ = false;
  std::int64_t whole_vertices_ = 0, whole_faces_ = 0;  // the whole boundary's (BoundaryMap)
  std::size_t owned_vertices_ = 0;  // the part's boundary vertices [0, owned) are this rank's
  // A part-only view's conditions as RestoreAppliedConditions read them, until placed.
  BoundaryConditions::Applied read_conditions_;
  MPI_Comm comm_;
  std::vector<FieldId> part_field_;  // the part's field behind each of the view's
  [[nodiscard]] const Layout& LayoutOf(FieldLocation location) const;
  [[nodiscard]] const std::vector<int>& WholeOfLocal(FieldLocation location) const;

  Layout nodes_, elements_, boundary_vertices_, boundary_faces_;
  std::uint64_t partition_fingerprint_ = 0;  // of the whole-mesh indices of the local nodes/tets
  bool part_only_ = false;
  double whole_diagonal_ = 0;    // of the whole mesh's bounding box
  double region_tolerance_ = 0;  // RegionTolerance of the whole mesh
  // The constructors' shared part: fingerprint, bounding box.
  void Describe();
  // RestoreObjectState from a checkpoint of `saved.size` ranks, another count (`at`: where the
  // DistributedPart section starts in `in`, to find it in the other ranks' files).
  // With `one_process`, `in` holds the serial object's state at `at` (`saved` then describes it
  // as the one part of a run on one rank: OneProcessPart).
  void RestoreOnAnotherRankCount(StateReader& in, const StateReader::Position& at,
                                 const SavedPart& saved, bool one_process = false);
  [[nodiscard]] SavedPart OneProcessPart() const;
  // RestoreObjectState from the files of a distributed run (a DistributedPart section at `at`).
  void RestoreFromParts(StateReader& in, const StateReader::Position& at);
  // Reads the serial object's state at `at` in `in` as rows (`counts` items), and its clock
  // from its header, which SimObject::RestoreState has read before: again, from `file`.
  SimObject::SavedHeader ReadOneProcessState(StateReader& in, const StateReader::Position& at,
                                             const std::filesystem::path& file,
                                             const ItemCounts& counts, StateRows& rows) const;
  // ShareOwnedNodeValues' ghosted PETSc Vecs, one per component count.
  struct NodeExchange;
  mutable std::unique_ptr<NodeExchange> exchange_;
  mutable std::int64_t whole_field_reads_ = 0;
  // Buffers of the gathers, kept between reads (no allocation once sized).
  mutable std::vector<double> receive_;
  mutable std::vector<int> counts_, offsets_;
  mutable Eigen::MatrixXd local_;
  mutable std::vector<int> sent_items_, received_items_;
  mutable std::vector<double> sent_values_;
  mutable std::vector<int> local_items_, positions_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
