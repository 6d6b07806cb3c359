// The MPI test program's main: PETSc (and MPI) for the whole run, GoogleTest's report from rank
// 0 only, the failed assertions of the other ranks (with their rank), and one exit code for all
// ranks (any rank's failure fails the program).

#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdio>

#include "gipsi/parallel/parallel_session.h"

namespace {

// Prints a failed assertion of a rank other than 0, which has no report of its own.
class RankFailurePrinter final : public ::testing::EmptyTestEventListener {
 public:
  explicit RankFailurePrinter(int rank) : rank_(rank) {}
  void OnTestPartResult(const ::testing::TestPartResult& result) override {
    if (!result.failed()) return;
    std::fprintf(stderr, "[rank %d] %s:%d: Failure\n%s\n", rank_,
                 result.file_name() != nullptr ? result.file_name() : "?", result.line_number(),
                 result.summary());
    std::fflush(stderr);
  }

 private:
  int rank_;
};

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  gipsi::ParallelSession session(&argc, &argv);
  const MPI_Comm world = gipsi::ParallelSession::world();
  const int rank = gipsi::ParallelSession::rank(world);
  if (rank != 0) {
    ::testing::TestEventListeners& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
    listeners.Append(new RankFailurePrinter(rank));
  }
  int failed = RUN_ALL_TESTS() != 0 ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, world);
  return failed;
}
