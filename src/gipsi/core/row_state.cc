/// @file
/// SavedPart's reader and the pieces of the checkpoint being resumed.

#include "gipsi/core/row_state.h"

#include <mutex>
#include <utility>

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
  saved.local.nodes = in.ReadInt();
  saved.boundary_vertices = in.ReadInt();
  saved.local.faces = in.ReadInt();
  in.ReadArray(saved.owned);
  in.ReadArray(saved.tets);
  in.ReadArray(saved.faces);
  saved.local.tets = static_cast<std::int64_t>(saved.tets.size());
  if (saved.size < 1 || saved.rank < 0 || saved.rank >= saved.size || saved.local.nodes < 0 ||
      saved.boundary_vertices < 0 || saved.local.faces < 0 ||
      static_cast<std::int64_t>(saved.owned.size()) > saved.local.nodes ||
      (!saved.faces.empty() && static_cast<std::int64_t>(saved.faces.size()) != saved.local.faces))
    in.Fail("a corrupted part header");
  return saved;
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
