#pragma once
// Checkpoint files of split objects written by some ranks of MPI_COMM_WORLD and read by others
// (checkpoint_ranks_test.cc, checkpoint_conditions_test.cc). Every call is collective over the
// communicator it is given (Folder: the world).

#include <fmt/format.h>
#include <mpi.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "gipsi/base/state.h"
#include "gipsi/parallel/parallel_session.h"
#include "gipsi/parallel/whole_domain_view.h"

namespace gipsi::test {

inline MPI_Comm World() { return ParallelSession::world(); }
inline int Rank(MPI_Comm comm) { return ParallelSession::rank(comm); }
inline int Size(MPI_Comm comm) { return ParallelSession::size(comm); }

// The first `ranks` ranks of the world (MPI_COMM_NULL on the others). Freed with the object.
class FirstRanks {
 public:
  explicit FirstRanks(int ranks) {
    MPI_Comm_split(World(), Rank(World()) < ranks ? 0 : MPI_UNDEFINED, Rank(World()), &comm_);
  }
  ~FirstRanks() {
    if (comm_ != MPI_COMM_NULL) MPI_Comm_free(&comm_);
  }
  FirstRanks(const FirstRanks&) = delete;
  FirstRanks& operator=(const FirstRanks&) = delete;
  [[nodiscard]] MPI_Comm comm() const { return comm_; }
  [[nodiscard]] bool member() const { return comm_ != MPI_COMM_NULL; }

 private:
  MPI_Comm comm_ = MPI_COMM_NULL;
};

// A folder of checkpoint files every rank of the world names alike.
inline std::filesystem::path Folder(const std::string& name) {
  int id = Rank(World()) == 0 ? static_cast<int>(::getpid()) : 0;
  MPI_Bcast(&id, 1, MPI_INT, 0, World());
  const auto folder =
      std::filesystem::temp_directory_path() / fmt::format("gipsi_ranks_{}_{}", name, id);
  if (Rank(World()) == 0) std::filesystem::create_directories(folder);
  MPI_Barrier(World());
  return folder;
}

// Every rank of `comm` writes the view's checkpoint to folder/p<rank>; returns every name.
inline std::vector<std::filesystem::path> Write(const WholeDomainView& view, MPI_Comm comm,
                                                const std::filesystem::path& folder) {
  StateWriter out;
  view.SaveState(out);
  std::vector<std::filesystem::path> files;
  for (int r = 0; r < Size(comm); ++r) files.push_back(folder / fmt::format("p{}", r));
  WriteCheckpointFile(files[static_cast<std::size_t>(Rank(comm))], out.bytes());
  return files;
}

// Restores `view` on its ranks from `files` (rank q reads file q % N, as the tool does).
inline void Restore(WholeDomainView& view, MPI_Comm comm,
                    const std::vector<std::filesystem::path>& files) {
  WholeDomainView::SetCheckpointFiles(files);
  const auto& mine = files[static_cast<std::size_t>(Rank(comm)) % files.size()];
  StateReader in(ReadCheckpointFile(mine), mine.string());
  try {
    view.RestoreState(in);
  } catch (...) {
    WholeDomainView::SetCheckpointFiles({});
    throw;
  }
  WholeDomainView::SetCheckpointFiles({});
}

}  // namespace gipsi::test
