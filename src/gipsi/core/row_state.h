#pragma once
/// @file
/// `RowState`: capability of an object whose state is rows of values per item of its domain
/// (nodes, tets, boundary faces) plus values that do not depend on the items (a clock, a solver
/// count), so that the state can move between objects of the same type on other items: a split
/// object's part restored on another partition, a checkpoint resumed on another rank count
/// (gipsi/parallel/whole_domain_view.h, docs/scale-out.md). The rows are read from and written
/// in the type's own checkpoint format (SaveObjectState's bytes), so nothing else changes.
/// EpTissue (the monodomains, serial and split) and FemSolid have it.
///
/// A split object's checkpoint holds, before its part's state, where the part's items are in
/// the whole domain (SavedPart, written by gipsi/parallel/whole_domain_view.h): a run of another
/// rank count, or on one process, reads the parts' rows and puts them where they belong.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/state.h"
#include "gipsi/core/boundary_conditions.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// How many items of each kind an object's domain has. Plain struct.
struct ItemCounts {
  std::int64_t nodes = 0, tets = 0, faces = 0;  ///< faces: of the boundary
};

/// A state as rows: each kind's rows item after item (width values each, 0: none of that kind),
/// and the rest as bytes that are the same for every part of one object. Plain struct.
struct StateRows {
  int node_width = 0, tet_width = 0, face_width = 0;
  std::vector<double> node, tet, face;
  std::string shared;
};

/// What the applied boundary conditions in a split object's SimObject section are: none (it
/// keeps no store), the whole boundary's (a view with the whole mesh), or its part's (a
/// part-only view: its part's boundary vertices and faces, in the part's order).
enum class SavedConditions : std::int64_t { kNone = 0, kWhole = 1, kPart = 2 };

/// What a split object's checkpoint holds before its part's state, in its section
/// kSavedPartTag (version kSavedPartVersion): the rank count and rank that wrote it, a
/// fingerprint of the partition, the whole domain's counts, the kind of conditions its
/// SimObject section holds, and the whole-domain indices of the part's owned nodes, of its tets,
/// of its boundary faces and of its owned boundary vertices (the last two empty when it keeps no
/// boundary conditions). Plain struct.
struct SavedPart {
  std::int64_t size = 0, rank = 0, whole_nodes = 0, whole_tets = 0, whole_faces = 0;
  std::int64_t whole_vertices = 0;  ///< the whole boundary's vertices
  std::uint64_t fingerprint = 0;
  SavedConditions conditions = SavedConditions::kNone;
  std::int64_t boundary_vertices = 0;
  ItemCounts local;           ///< the part's nodes, tets and boundary faces
  std::vector<int> owned;     ///< whole-domain indices of the owned nodes (local [0, owned))
  std::vector<int> tets;      ///< of every local tet
  std::vector<int> faces;     ///< the whole boundary's face of every part face, or none
  std::vector<int> vertices;  ///< the whole boundary's vertex of each owned part boundary
                              ///< vertex (the part's first ones), or none
};
inline constexpr std::string_view kSavedPartTag = "DistributedPart";
inline constexpr std::uint32_t kSavedPartVersion = 3;
/// Reads a SavedPart's fields (its section entered). Throws InputError for a corrupted one.
[[nodiscard]] SavedPart ReadSavedPart(StateReader& in);
/// From the start of a checkpoint file's data (`fresh`, nothing read yet): reads the applied
/// boundary conditions in the SimObject section of the split object whose DistributedPart
/// section is at `part_at` (found in another rank's file of the same checkpoint), and leaves
/// `fresh` at `part_at`, as Seek(part_at) would. Throws InputError if the file's layout
/// differs there.
[[nodiscard]] BoundaryConditions::Applied SeekPartReadingConditions(
    StateReader& fresh, const StateReader::Position& part_at);

/// The files of a distributed checkpoint being resumed (every rank's, rank 0's first), which
/// the tool sets before Kernel::ReadCheckpoint so that split objects (or, in a run on one
/// process, the serial objects) read the parts in them; empty when none is being resumed.
/// Thread-safe.
void SetCheckpointPieces(std::vector<std::filesystem::path> files);
[[nodiscard]] std::vector<std::filesystem::path> CheckpointPieces();

/// Interface, implemented beside SimObject; asked for with dynamic_cast. Not copyable.
class RowState {
 public:
  RowState() = default;
  RowState(const RowState&) = delete;
  RowState& operator=(const RowState&) = delete;
  virtual ~RowState() = default;

  /// Reads the type's state as SaveObjectState wrote it for an object of this type and
  /// configuration whose domain had `counts` items (another part's), as rows. Solver caches
  /// that hold nothing but the bits of a continuation (a kept factorisation) are skipped.
  /// Throws InputError for data of another layout.
  [[nodiscard]] virtual StateRows ReadStateRows(StateReader& in,
                                                const ItemCounts& counts) const = 0;
  /// Writes the type's state in SaveObjectState's format for this object, from rows of its own
  /// items (in its order) and the shared bytes (with empty solver caches). Throws InputError if
  /// the widths or the shared bytes do not fit this object.
  virtual void WriteStateRows(StateWriter& out, const StateRows& rows) const = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
