/// @file
/// SavedPart's reader and the pieces of the checkpoint being resumed.

#include "gipsi/core/row_state.h"

#include <mutex>
#include <utility>

#include "gipsi/base/error.h"

namespace gipsi {
namespace {

std::mutex pieces_mutex;
std::vector<std::filesystem::path>& Pieces() {
  static std::vector<std::filesystem::path> files;
  return files;
}

}  // namespace

SavedPart ReadSavedPart(StateReader& in) {
  SavedPart saved;
  saved.size = in.ReadInt();
  saved.rank = in.ReadInt();
  saved.fingerprint = static_cast<std::uint64_t>(in.ReadInt());
  saved.whole_nodes = in.ReadInt();
  saved.whole_tets = in.ReadInt();
  saved.whole_faces = in.ReadInt();
  saved.whole_vertices = in.ReadInt();
  const std::int64_t conditions = in.ReadInt();
  saved.local.nodes = in.ReadInt();
  saved.boundary_vertices = in.ReadInt();
  saved.local.faces = in.ReadInt();
  in.ReadArray(saved.owned);
  in.ReadArray(saved.tets);
  in.ReadArray(saved.faces);
  in.ReadArray(saved.vertices);
  saved.local.tets = static_cast<std::int64_t>(saved.tets.size());
  if (saved.size < 1 || saved.rank < 0 || saved.rank >= saved.size || saved.local.nodes < 0 ||
      saved.boundary_vertices < 0 || saved.local.faces < 0 || conditions < 0 || conditions > 2 ||
      static_cast<std::int64_t>(saved.owned.size()) > saved.local.nodes ||
      (!saved.faces.empty() &&
       static_cast<std::int64_t>(saved.faces.size()) != saved.local.faces) ||
      static_cast<std::int64_t>(saved.vertices.size()) > saved.boundary_vertices)
    in.Fail("a corrupted part header");
  saved.conditions = static_cast<SavedConditions>(conditions);
  return saved;
}

BoundaryConditions::Applied SeekPartReadingConditions(StateReader& fresh,
                                                      const StateReader::Position& part_at) {
  // `part_at` is inside the object's type section, itself inside its SimObject section, whose
  // first entries are the header (name, type, time, steps) and the applied conditions.
  GIPSI_CHECK(part_at.index.size() >= 3 && part_at.tags.size() >= 2);
  StateReader::Position header_at = part_at;
  header_at.index.resize(header_at.index.size() - 2);
  header_at.index.push_back(0);
  header_at.tags.pop_back();
  header_at.versions.pop_back();
  fresh.Seek(header_at);
  fresh.SkipEntries(4);
  BoundaryConditions::Applied applied = BoundaryConditions::ReadAnySize(fresh);
  fresh.BeginSection(part_at.tags.back(), part_at.versions.back());
  fresh.SkipEntries(static_cast<int>(part_at.index.back()));
  if (fresh.position().index != part_at.index)
    fresh.Fail("the object's section is laid out differently from the other ranks' files");
  return applied;
}

void SetCheckpointPieces(std::vector<std::filesystem::path> files) {
  const std::lock_guard lock(pieces_mutex);
  Pieces() = std::move(files);
}

std::vector<std::filesystem::path> CheckpointPieces() {
  const std::lock_guard lock(pieces_mutex);
  return Pieces();
}

}  // namespace gipsi
