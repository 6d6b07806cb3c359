/// @file
/// WholeDomainView's checkpoints: this rank's part, restored on the rank count that wrote it
/// (bitwise) or, for a part whose state is per node, on another (docs/scale-out.md).

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <numeric>
#include <string>
#include <utility>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/core/row_state.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/whole_domain_view.h"

namespace gipsi {
namespace {

// Fails every rank together: each learns whether any rank failed before going on, so none
// waits in a collective the others never reach. `mine` is empty where this rank did not fail.
// The message names `in`'s file and section, or only `source` where given (a refusal of the
// whole set of files, the same words on every rank: printed once).
void FailTogether(StateReader& in, const std::string& mine, MPI_Comm comm,
                  const std::string& source = {}) {
  int failed = mine.empty() ? 0 : 1, any = 0;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, comm);
  if (any == 0) return;
  const std::string what =
      mine.empty() ? "another rank's checkpoint file was refused (see its message)" : mine;
  if (!source.empty()) throw InputError(fmt::format("{}: {}", source, what));
  in.Fail(what);
}

}  // namespace

void WholeDomainView::SetCheckpointFiles(std::vector<std::filesystem::path> files) {
  SetCheckpointPieces(std::move(files));
}

void WholeDomainView::SaveObjectState(StateWriter& out) const {
  out.BeginSection(kSavedPartTag, kSavedPartVersion);
  out.WriteInt(mesh_part_.size);
  out.WriteInt(mesh_part_.rank);
  out.WriteInt(static_cast<std::int64_t>(partition_fingerprint_));
  // What another rank count needs to read the part: its items and where they are in the whole.
  out.WriteInt(mesh_part_.num_global_nodes);
  out.WriteInt(mesh_part_.num_global_tets);
  out.WriteInt(whole_boundary_faces());
  out.WriteInt(forward_bcs_ ? whole_vertices_ : 0);
  out.WriteInt(static_cast<std::int64_t>(saved_conditions()));
  out.WriteInt(mesh_part_.num_local());
  out.WriteInt(part_->boundary_conditions().num_vertices());
  out.WriteInt(part_->boundary().num_triangles());
  out.WriteArray(std::span<const int>(mesh_part_.whole_node.data(),
                                      static_cast<std::size_t>(mesh_part_.num_owned)));
  out.WriteArray(mesh_part_.whole_tet);
  out.WriteArray(forward_bcs_ ? std::span<const int>(bc_face_) : std::span<const int>());
  out.WriteArray(forward_bcs_ ? std::span<const int>(bc_vertex_.data(), owned_vertices_)
                              : std::span<const int>());
  part_->SaveState(out);
  out.EndSection();
}

SavedConditions WholeDomainView::saved_conditions() const {
  if (!part_only_) return SavedConditions::kWhole;  // SimObject's store, on the whole boundary
  return forward_bcs_ ? SavedConditions::kPart : SavedConditions::kNone;
}

void WholeDomainView::RestoreAppliedConditions(StateReader& in) {
  if (!part_only_) {  // a store on the whole boundary
    SimObject::RestoreAppliedConditions(in);
    return;
  }
  read_conditions_ = BoundaryConditions::ReadAnySize(in);
}

std::string WholeDomainView::PlaceReadConditions(SavedConditions kept) {
  BoundaryConditions::Applied read = std::move(read_conditions_);
  read_conditions_ = {};
  const Index vertices = read.value.cols(), faces = read.pressure.size();
  if (!forward_bcs_) {
    if (BoundaryConditions::AppliesNothing(read)) return {};
    return fmt::format(
        "the checkpoint holds boundary conditions of object '{}', which this run keeps in parts "
        "without a boundary-condition store",
        name());
  }
  BoundaryConditions& store = boundary_conditions();
  if (kept == SavedConditions::kNone) return {};  // nothing was set: the scene's stay
  if (kept == SavedConditions::kPart) {           // this part's own (same partition)
    if (vertices != store.num_vertices() || faces != store.num_faces())
      return fmt::format(
          "the checkpoint's part has boundary conditions on {} vertices and {} faces, and this "
          "rank's part of object '{}' has {} and {}",
          vertices, faces, name(), store.num_vertices(), store.num_faces());
    store.RestoreApplied(std::move(read));
    return {};
  }
  // The whole boundary's (a serial object's, or a view's with the whole mesh): this part's rows.
  if (vertices != whole_vertices_ || faces != whole_faces_)
    return fmt::format(
        "the checkpoint has boundary conditions on {} vertices and {} faces, and the whole "
        "boundary of object '{}' has {} and {}",
        vertices, faces, name(), whole_vertices_, whole_faces_);
  BoundaryConditions::Applied mine = store.applied();
  std::array<double, BoundaryConditions::Applied::kVertexRow> row{};
  for (std::size_t v = 0; v < bc_vertex_.size(); ++v) {
    read.VertexRow(bc_vertex_[v], row.data());
    mine.SetVertexRow(static_cast<Index>(v), row.data());
  }
  for (std::size_t f = 0; f < bc_face_.size(); ++f) {
    read.FaceRow(bc_face_[f], row.data());
    mine.SetFaceRow(static_cast<Index>(f), row.data());
  }
  store.RestoreApplied(std::move(mine));
  return {};
}

void WholeDomainView::MoveConditions(StateReader& in, const std::vector<int>& vertex_of,
                                     std::vector<double>& vertex_rows,
                                     const std::vector<int>& face_of,
                                     std::vector<double>& face_rows) {
  constexpr int kVertexRow = BoundaryConditions::Applied::kVertexRow;
  constexpr int kFaceRow = BoundaryConditions::Applied::kFaceRow;
  const MovedRows vertices =
      MoveRows(bc_vertex_, whole_vertices_, vertex_of, vertex_rows, kVertexRow, comm_);
  const MovedRows faces = MoveRows(bc_face_, whole_faces_, face_of, face_rows, kFaceRow, comm_);
  for (const auto& [moved, what] :
       {std::pair{&vertices, "boundary vertex"}, std::pair{&faces, "boundary face"}})
    if (moved->missing > 0 || moved->repeated > 0 || moved->outside > 0)
      in.Fail(fmt::format(
          "the checkpoint's parts do not hold every {} of this scene's mesh once ({} missing, "
          "the first {}; {} given twice; {} not in the mesh): it was written for another mesh",
          what, moved->missing, moved->first_missing, moved->repeated, moved->outside));
  BoundaryConditions::Applied mine = boundary_conditions().applied();
  for (std::size_t v = 0; v < bc_vertex_.size(); ++v)
    mine.SetVertexRow(static_cast<Index>(v), &vertices.rows[v * kVertexRow]);
  for (std::size_t f = 0; f < bc_face_.size(); ++f)
    mine.SetFaceRow(static_cast<Index>(f), &faces.rows[f * kFaceRow]);
  boundary_conditions().RestoreApplied(std::move(mine));
}

SavedPart WholeDomainView::OneProcessPart() const {
  SavedPart saved;
  saved.size = 1;
  saved.whole_nodes = saved.local.nodes = mesh_part_.num_global_nodes;
  saved.whole_tets = saved.local.tets = mesh_part_.num_global_tets;
  saved.whole_faces = saved.local.faces = whole_boundary_faces();
  saved.whole_vertices = forward_bcs_ ? whole_vertices_ : 0;
  saved.conditions = SavedConditions::kWhole;  // a serial object's store
  saved.owned.resize(static_cast<std::size_t>(saved.whole_nodes));
  std::iota(saved.owned.begin(), saved.owned.end(), 0);
  saved.tets.resize(static_cast<std::size_t>(saved.whole_tets));
  std::iota(saved.tets.begin(), saved.tets.end(), 0);
  saved.faces.resize(static_cast<std::size_t>(saved.whole_faces));
  std::iota(saved.faces.begin(), saved.faces.end(), 0);
  return saved;
}

void WholeDomainView::RestoreObjectState(StateReader& in) {
  const StateReader::Position at = in.position();
  // A checkpoint of a run on one process holds the serial object's state here (every rank reads
  // that one file, so all take the same way).
  const bool one_process = !in.NextIsSection(kSavedPartTag);
  if (one_process) {
    RestoreOnAnotherRankCount(in, at, OneProcessPart(), true);
  } else {
    RestoreFromParts(in, at);
  }
  // The files of one checkpoint hold the same time and step count on every rank; a set mixed
  // from two checkpoints (a run stopped while its ranks wrote them) does not.
  const std::array<double, 2> local{part_->time(), static_cast<double>(part_->step_count())};
  std::array<double, 2> low{}, high{};
  MPI_Allreduce(local.data(), low.data(), 2, MPI_DOUBLE, MPI_MIN, comm_);
  MPI_Allreduce(local.data(), high.data(), 2, MPI_DOUBLE, MPI_MAX, comm_);
  if (low != high)
    in.Fail(fmt::format(
        "the ranks' checkpoint files are from different checkpoints (object '{}' at t = {:.9g} "
        "to {:.9g} s, {} to {} steps): resume from a set written together",
        name(), low[0], high[0], low[1], high[1]));
}

SimObject::SavedHeader WholeDomainView::ReadOneProcessState(StateReader& in,
                                                            const StateReader::Position& at,
                                                            const std::filesystem::path& file,
                                                            const ItemCounts& counts,
                                                            StateRows& rows) const {
  rows = dynamic_cast<const RowState&>(*part_).ReadStateRows(in, counts);
  in.SkipRestOfSection();  // a serial solver's cache, not moved
  // `at` is inside the object's SimObject section and its type's: the header is the first
  // entries of the former.
  StateReader::Position header_at = at;
  GIPSI_CHECK(header_at.index.size() >= 3 && header_at.tags.size() >= 2);
  header_at.index.resize(header_at.index.size() - 2);
  header_at.index.push_back(0);
  header_at.tags.pop_back();
  header_at.versions.pop_back();
  StateReader again(ReadCheckpointFile(file), file.string());
  again.Seek(header_at);
  SimObject::SavedHeader header;
  header.name = again.ReadString();
  header.type = again.ReadString();
  header.time = again.ReadDouble();
  header.steps = again.ReadInt();
  return header;
}

void WholeDomainView::RestoreFromParts(StateReader& in, const StateReader::Position& at) {
  in.BeginSection(kSavedPartTag, kSavedPartVersion);
  const SavedPart saved = ReadSavedPart(in);
  // Every rank decides which way to restore from its own file's header; they agree when the
  // files are one checkpoint's (checked below).
  int other_count = saved.size != mesh_part_.size ? 1 : 0, all_other = 0;
  MPI_Allreduce(&other_count, &all_other, 1, MPI_INT, MPI_MIN, comm_);
  if (all_other != 0) {
    RestoreOnAnotherRankCount(in, at, saved);
  } else {
    std::string refused;
    if (saved.size != mesh_part_.size)
      refused = fmt::format(
          "the ranks' files hold parts of runs on different rank counts (this one {} ranks): "
          "resume from the files of one checkpoint",
          saved.size);
    else if (saved.rank != mesh_part_.rank)
      refused = fmt::format("the checkpoint holds rank {}'s part, and this is rank {}", saved.rank,
                            mesh_part_.rank);
    else if (saved.fingerprint != partition_fingerprint_)
      refused =
          "the checkpoint's part of the mesh differs from this run's partition on the same rank "
          "count (another mesh, or a partitioner that cut it differently: another PETSc or "
          "PT-Scotch build)";
    if (refused.empty() && part_only_) refused = PlaceReadConditions(saved.conditions);
    FailTogether(in, refused, comm_);
    part_->RestoreState(in);
  }
  in.EndSection();
}

void WholeDomainView::RestoreOnAnotherRankCount(StateReader& in, const StateReader::Position& at,
                                                const SavedPart& saved, bool one_process) {
  const int ranks = mesh_part_.size, rank = mesh_part_.rank;
  const auto* movable = dynamic_cast<const RowState*>(part_.get());
  const std::vector<std::filesystem::path> files = CheckpointPieces();
  const std::int64_t whole_faces = whole_boundary_faces();
  std::string refused;
  if (movable == nullptr)
    refused = one_process ? fmt::format(
                                "the checkpoint was written by a run on one process and this "
                                "run has {} ranks: a split {} does not take a serial object's "
                                "state yet; resume it without mpirun",
                                ranks, type_name())
                          : fmt::format(
                                "the checkpoint was written on {} ranks and this run has {}: a "
                                "split {} resumes only on the rank count that wrote it (its "
                                "state does not move to another yet): mpirun -np {}",
                                saved.size, ranks, type_name(), saved.size);
  else if (one_process && files.size() != 1)
    refused =
        "a checkpoint of a run on one process is read from its one file (gipsi run "
        "--resume finds it)";
  else if (!one_process && files.empty())
    refused = fmt::format(
        "the checkpoint holds rank {}'s part of a run on {} ranks, and this run has {}; to "
        "resume on another rank count the restore needs every rank's file (gipsi run --resume "
        "finds them), or resume with mpirun -np {}",
        saved.rank, saved.size, ranks, saved.size);
  else if (!one_process && static_cast<std::int64_t>(files.size()) != saved.size)
    refused = fmt::format(
        "the checkpoint's parts were written on {} ranks, and {} files were found ({} to {}): "
        "the set mixes checkpoints of different rank counts",
        saved.size, files.size(), files.front().string(), files.back().string());
  else if (saved.whole_nodes != mesh_part_.num_global_nodes ||
           saved.whole_tets != mesh_part_.num_global_tets || saved.whole_faces != whole_faces)
    refused = fmt::format(
        "the checkpoint's mesh has {} nodes, {} tets and {} boundary faces, and this scene's "
        "has {}, {} and {}",
        saved.whole_nodes, saved.whole_tets, saved.whole_faces, mesh_part_.num_global_nodes,
        mesh_part_.num_global_tets, whole_faces);
  // A part-only view's conditions: the whole boundary's are placed now; the parts' move below.
  const bool move_conditions =
      part_only_ && forward_bcs_ && saved.conditions == SavedConditions::kPart;
  std::array<int, 2> moving{move_conditions ? 1 : 0, move_conditions ? 0 : 1};
  MPI_Allreduce(MPI_IN_PLACE, moving.data(), 2, MPI_INT, MPI_MAX, comm_);
  if (refused.empty() && moving[0] == 1 && moving[1] == 1)  // every rank must move, or none
    refused =
        "the ranks' files keep the object's boundary conditions differently: they are "
        "not one checkpoint's";
  BoundaryConditions::Applied own_conditions;
  if (refused.empty() && part_only_) {
    if (move_conditions) {
      own_conditions = std::move(read_conditions_);
      read_conditions_ = {};
    } else {
      refused = PlaceReadConditions(saved.conditions);
    }
  }
  FailTogether(in, refused, comm_,
               files.empty() ? std::string()
                             : fmt::format("{} (object '{}')", files.front().string(), name()));

  // Rank q reads the parts of ranks q, q + M, ... of the N that wrote the checkpoint; its own
  // file (that of rank q % N) is one of them when q < N. It keeps the rows of the owned nodes,
  // of every tet and every boundary face (each on one part), with their whole-mesh indices.
  StateRows mine;
  std::vector<int> node_of, tet_of, face_of;
  std::vector<int> condition_vertex_of, condition_face_of;  // the whole boundary's items
  std::vector<double> condition_vertex_rows, condition_face_rows;
  std::string common;  // the clock, the widths and the shared bytes: the same in every file
  std::string failed;
  auto read_part = [&](StateReader& from, const SavedPart& part, std::int64_t expected_rank,
                       const BoundaryConditions::Applied& conditions) {
    if (part.size != saved.size || part.rank != expected_rank)
      from.Fail(
          fmt::format("this file holds rank {}'s part of {} where rank {}'s part of {} was "
                      "expected: the set mixes checkpoints",
                      part.rank, part.size, expected_rank, saved.size));
    if (move_conditions) {  // the rows of the part's own vertices and of its faces
      if (part.conditions != SavedConditions::kPart ||
          conditions.value.cols() != part.boundary_vertices ||
          conditions.pressure.size() != part.local.faces ||
          static_cast<std::int64_t>(part.faces.size()) != part.local.faces)
        from.Fail("the part's boundary conditions do not fit its boundary: a corrupted file");
      constexpr int kVertexRow = BoundaryConditions::Applied::kVertexRow;
      constexpr int kFaceRow = BoundaryConditions::Applied::kFaceRow;
      std::size_t at_row = condition_vertex_rows.size();
      condition_vertex_rows.resize(at_row + part.vertices.size() * kVertexRow);
      for (std::size_t v = 0; v < part.vertices.size(); ++v, at_row += kVertexRow)
        conditions.VertexRow(static_cast<Index>(v), &condition_vertex_rows[at_row]);
      at_row = condition_face_rows.size();
      condition_face_rows.resize(at_row + part.faces.size() * kFaceRow);
      for (std::size_t f = 0; f < part.faces.size(); ++f, at_row += kFaceRow)
        conditions.FaceRow(static_cast<Index>(f), &condition_face_rows[at_row]);
      condition_vertex_of.insert(condition_vertex_of.end(), part.vertices.begin(),
                                 part.vertices.end());
      condition_face_of.insert(condition_face_of.end(), part.faces.begin(), part.faces.end());
    }
    StateRows rows;
    const SimObject::SavedHeader header =
        one_process ? ReadOneProcessState(from, at, files.front(), part.local, rows)
                    : SimObject::ReadSavedState(from, part.boundary_vertices, part.local.faces,
                                                [&](StateReader& own) {
                                                  rows = movable->ReadStateRows(own, part.local);
                                                });
    if (header.name != part_->name() || header.type != part_->type_name())
      from.Fail(fmt::format("the checkpoint has object '{}' ({}) where this scene has '{}' ({})",
                            header.name, header.type, part_->name(), part_->type_name()));
    if (rows.face_width > 0 && part.faces.empty())
      from.Fail("the part's boundary faces have state but no place on the whole boundary");
    auto keep = [](std::vector<double>& to, const std::vector<double>& from_rows, int width,
                   std::size_t count) {
      to.insert(
          to.end(), from_rows.begin(),
          from_rows.begin() + static_cast<std::ptrdiff_t>(count * static_cast<std::size_t>(width)));
    };
    keep(mine.node, rows.node, rows.node_width, part.owned.size());
    keep(mine.tet, rows.tet, rows.tet_width, rows.tet_width > 0 ? part.tets.size() : 0);
    keep(mine.face, rows.face, rows.face_width, rows.face_width > 0 ? part.faces.size() : 0);
    node_of.insert(node_of.end(), part.owned.begin(), part.owned.end());
    if (rows.tet_width > 0) tet_of.insert(tet_of.end(), part.tets.begin(), part.tets.end());
    if (rows.face_width > 0) face_of.insert(face_of.end(), part.faces.begin(), part.faces.end());
    StateWriter c;
    c.WriteDouble(header.time);
    c.WriteInt(header.steps);
    c.WriteInt(rows.node_width);
    c.WriteInt(rows.tet_width);
    c.WriteInt(rows.face_width);
    c.WriteString(rows.shared);
    common = c.TakeBytes();
  };
  try {
    if (rank < saved.size) {
      read_part(in, saved, rank, own_conditions);
    } else {
      in.SkipRestOfSection();  // rank q % N reads this one
    }
    for (std::int64_t r = rank + ranks; r < saved.size; r += ranks) {
      const std::filesystem::path& file = files[static_cast<std::size_t>(r)];
      StateReader other(ReadCheckpointFile(file), file.string());
      BoundaryConditions::Applied conditions;
      if (move_conditions)
        conditions = SeekPartReadingConditions(other, at);
      else
        other.Seek(at);
      other.BeginSection(kSavedPartTag, kSavedPartVersion);
      const std::string before = common;
      read_part(other, ReadSavedPart(other), r, conditions);
      if (!before.empty() && before != common)
        other.Fail("this file is from another checkpoint than the others this rank read");
      other.EndSection();
    }
  } catch (const InputError& e) {
    failed = e.what();
  }
  {  // like FailTogether, with the message the reader already formatted
    int failing = failed.empty() ? 0 : 1, any = 0;
    MPI_Allreduce(&failing, &any, 1, MPI_INT, MPI_MAX, comm_);
    if (any != 0)
      throw InputError(failed.empty()
                           ? fmt::format("{}: another rank's checkpoint file was refused (see its "
                                         "message)",
                                         files.front().string())
                           : failed);
  }

  // Every file of one checkpoint has the same clock, widths and shared state. Rank 0 read
  // file 0; a rank that read none takes its values.
  auto length = static_cast<int>(common.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, comm_);
  std::string first = rank == 0 ? common : std::string(static_cast<std::size_t>(length), '\0');
  MPI_Bcast(first.data(), length, MPI_CHAR, 0, comm_);
  int differs = rank < saved.size && common != first ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &differs, 1, MPI_INT, MPI_MAX, comm_);
  if (differs != 0)
    in.Fail(
        fmt::format("the ranks' checkpoint files are from different checkpoints (object "
                    "'{}'): resume from a set written together",
                    name()));
  StateReader agreed(first, in.source());
  const double time = agreed.ReadDouble();
  const std::int64_t steps = agreed.ReadInt();
  mine.node_width = static_cast<int>(agreed.ReadInt());
  mine.tet_width = static_cast<int>(agreed.ReadInt());
  mine.face_width = static_cast<int>(agreed.ReadInt());
  mine.shared = agreed.ReadString();

  // The rows go to the parts that hold their items.
  std::string lost;
  auto move = [&](const char* what, std::span<const int> held, std::int64_t count,
                  const std::vector<int>& of, std::vector<double>& rows, int width) {
    if (width == 0) return;
    MovedRows moved = MoveRows(held, count, of, rows, width, comm_);
    if (lost.empty() && (moved.missing > 0 || moved.repeated > 0 || moved.outside > 0))
      lost = fmt::format(
          "the checkpoint's parts do not hold every {} of this scene's mesh once ({} missing, "
          "the first {}; {} given twice; {} not in the mesh): it was written for another mesh",
          what, moved.missing, moved.first_missing, moved.repeated, moved.outside);
    rows = std::move(moved.rows);
  };
  move("node", mesh_part_.whole_node, mesh_part_.num_global_nodes, node_of, mine.node,
       mine.node_width);
  move("tet", mesh_part_.whole_tet, mesh_part_.num_global_tets, tet_of, mine.tet, mine.tet_width);
  if (mine.face_width > 0 && !forward_bcs_)
    lost = "the part's boundary faces have state but no place on the whole boundary";
  else
    move("boundary face", bc_face_, whole_faces, face_of, mine.face, mine.face_width);
  if (!lost.empty()) in.Fail(lost);
  if (move_conditions)
    MoveConditions(in, condition_vertex_of, condition_vertex_rows, condition_face_of,
                   condition_face_rows);
  part_->RestoreStateFrom(time, steps,
                          [&](StateWriter& out) { movable->WriteStateRows(out, mine); });
}

}  // namespace gipsi
