/// @file
/// WholeDomainView's checkpoints: this rank's part, restored on the rank count that wrote it
/// (bitwise) or, for a part whose state is per node, on another (docs/scale-out.md).

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <mutex>
#include <string>
#include <utility>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/parallel/node_state_part.h"
#include "gipsi/parallel/whole_domain_view.h"

namespace gipsi {
namespace {

std::mutex files_mutex;
std::vector<std::filesystem::path>& CheckpointFiles() {
  static std::vector<std::filesystem::path> files;
  return files;
}

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
  const std::lock_guard lock(files_mutex);
  CheckpointFiles() = std::move(files);
}

void WholeDomainView::SaveObjectState(StateWriter& out) const {
  out.BeginSection("DistributedPart", 2);
  out.WriteInt(mesh_part_.size);
  out.WriteInt(mesh_part_.rank);
  out.WriteInt(static_cast<std::int64_t>(partition_fingerprint_));
  // What another rank count needs to read the part: its size, boundary and owned nodes.
  out.WriteInt(mesh_part_.num_global_nodes);
  out.WriteInt(mesh_part_.num_local());
  out.WriteInt(part_->boundary_conditions().num_vertices());
  out.WriteInt(part_->boundary_conditions().num_faces());
  out.WriteArray(std::span<const int>(mesh_part_.whole_node.data(),
                                      static_cast<std::size_t>(mesh_part_.num_owned)));
  part_->SaveState(out);
  out.EndSection();
}

WholeDomainView::SavedPart WholeDomainView::ReadSavedPart(StateReader& in) {
  SavedPart saved;
  saved.size = in.ReadInt();
  saved.rank = in.ReadInt();
  saved.fingerprint = static_cast<std::uint64_t>(in.ReadInt());
  saved.whole_nodes = in.ReadInt();
  saved.local_nodes = in.ReadInt();
  saved.boundary_vertices = in.ReadInt();
  saved.boundary_faces = in.ReadInt();
  in.ReadArray(saved.owned);
  if (saved.size < 1 || saved.rank < 0 || saved.rank >= saved.size || saved.local_nodes < 0 ||
      saved.boundary_vertices < 0 || saved.boundary_faces < 0 ||
      static_cast<std::int64_t>(saved.owned.size()) > saved.local_nodes)
    in.Fail("a corrupted part header");
  return saved;
}

void WholeDomainView::RestoreObjectState(StateReader& in) {
  const StateReader::Position at = in.position();
  in.BeginSection("DistributedPart", 2);
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
    FailTogether(in, refused, comm_);
    part_->RestoreState(in);
  }
  in.EndSection();
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

void WholeDomainView::RestoreOnAnotherRankCount(StateReader& in, const StateReader::Position& at,
                                                const SavedPart& saved) {
  const int ranks = mesh_part_.size, rank = mesh_part_.rank;
  const auto* movable = dynamic_cast<const NodeStatePart*>(part_.get());
  std::vector<std::filesystem::path> files;
  {
    const std::lock_guard lock(files_mutex);
    files = CheckpointFiles();
  }
  std::string refused;
  if (movable == nullptr)
    refused = fmt::format(
        "the checkpoint was written on {} ranks and this run has {}: a split {} resumes only "
        "on the rank count that wrote it (a Monodomain's state moves to another; this type's "
        "does not yet): mpirun -np {}",
        saved.size, ranks, type_name(), saved.size);
  else if (files.empty())
    refused = fmt::format(
        "the checkpoint holds rank {}'s part of a run on {} ranks, and this run has {}; to "
        "resume on another rank count the restore needs every rank's file (gipsi run --resume "
        "finds them), or resume with mpirun -np {}",
        saved.rank, saved.size, ranks, saved.size);
  else if (static_cast<std::int64_t>(files.size()) != saved.size)
    refused = fmt::format(
        "the checkpoint's parts were written on {} ranks, and {} files were found ({} to {}): "
        "the set mixes checkpoints of different rank counts",
        saved.size, files.size(), files.front().string(), files.back().string());
  else if (saved.whole_nodes != mesh_part_.num_global_nodes)
    refused = fmt::format("the checkpoint's mesh has {} nodes, and this scene's has {}",
                          saved.whole_nodes, mesh_part_.num_global_nodes);
  FailTogether(in, refused, comm_,
               files.empty() ? std::string()
                             : fmt::format("{} (object '{}')", files.front().string(), name()));

  // Rank q reads the parts of ranks q, q + M, ... of the N that wrote the checkpoint; its own
  // file (that of rank q % N) is one of them when q < N.
  const int width = movable->node_row_width();
  std::vector<int> whole;
  std::vector<double> rows, shared;
  std::array<double, 2> clock{0, 0};  // time, steps
  std::string failed;
  auto read_part = [&](StateReader& from, const SavedPart& part, std::int64_t expected_rank) {
    if (part.size != saved.size || part.rank != expected_rank)
      from.Fail(
          fmt::format("this file holds rank {}'s part of {} where rank {}'s part of {} was "
                      "expected: the set mixes checkpoints",
                      part.rank, part.size, expected_rank, saved.size));
    std::vector<double> part_rows;
    const SimObject::SavedHeader header = SimObject::ReadSavedState(
        from, part.boundary_vertices, part.boundary_faces,
        [&](StateReader& own) { movable->ReadNodeRows(own, part.local_nodes, part_rows, shared); });
    if (header.name != part_->name() || header.type != part_->type_name())
      from.Fail(fmt::format("the checkpoint has object '{}' ({}) where this scene has '{}' ({})",
                            header.name, header.type, part_->name(), part_->type_name()));
    whole.insert(whole.end(), part.owned.begin(), part.owned.end());
    rows.insert(rows.end(), part_rows.begin(),
                part_rows.begin() + static_cast<std::ptrdiff_t>(part.owned.size() *
                                                                static_cast<std::size_t>(width)));
    clock = {header.time, static_cast<double>(header.steps)};
  };
  try {
    if (rank < saved.size) {
      read_part(in, saved, rank);
    } else {
      in.SkipRestOfSection();  // rank q % N reads this one
    }
    for (std::int64_t r = rank + ranks; r < saved.size; r += ranks) {
      const std::filesystem::path& file = files[static_cast<std::size_t>(r)];
      StateReader other(ReadCheckpointFile(file), file.string());
      other.Seek(at);
      other.BeginSection("DistributedPart", 2);
      read_part(other, ReadSavedPart(other), r);
      other.EndSection();
    }
  } catch (const InputError& e) {
    failed = e.what();
  }
  {  // like FailTogether, with the message the reader already formatted
    int mine = failed.empty() ? 0 : 1, any = 0;
    MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, comm_);
    if (any != 0)
      throw InputError(failed.empty()
                           ? fmt::format("{}: another rank's checkpoint file was refused (see its "
                                         "message)",
                                         files.front().string())
                           : failed);
  }

  // Every file of one checkpoint has the same clock and shared values. Rank 0 read file 0; a
  // rank that read none takes its values.
  std::vector<double> common(clock.begin(), clock.end());
  common.insert(common.end(), shared.begin(), shared.end());
  auto count = static_cast<int>(common.size());
  MPI_Bcast(&count, 1, MPI_INT, 0, comm_);
  std::vector<double> first = common;
  first.resize(static_cast<std::size_t>(count));
  MPI_Bcast(first.data(), count, MPI_DOUBLE, 0, comm_);
  if (rank >= saved.size) common = first;
  int differs = common != first ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &differs, 1, MPI_INT, MPI_MAX, comm_);
  if (differs != 0)
    in.Fail(
        fmt::format("the ranks' checkpoint files are from different checkpoints (object '{}' "
                    "at t = {:.9g} s in rank 0's): resume from a set written together",
                    name(), first[0]));

  const MovedNodeRows moved = MoveNodeRows(mesh_part_, whole, rows, width, comm_);
  if (moved.missing > 0 || moved.repeated > 0 || moved.outside > 0)
    in.Fail(fmt::format(
        "the checkpoint's parts do not hold every node of this scene's mesh once ({} nodes "
        "missing, the first {}; {} given twice; {} not in the mesh): it was written for another "
        "mesh",
        moved.missing, moved.first_missing, moved.repeated, moved.outside));
  const std::vector<double> state_shared(first.begin() + 2, first.end());
  part_->RestoreStateFrom(first[0], static_cast<std::int64_t>(first[1]), [&](StateWriter& out) {
    movable->WriteNodeRows(out, moved.rows, state_shared);
  });
}

}  // namespace gipsi
