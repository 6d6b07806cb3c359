// The MPI test program's main: PETSc (and MPI) for the whole run, GoogleTest's report from rank
// 0 only, and one exit code for all ranks (any rank's failure fails the program).

#include <gtest/gtest.h>
#include <mpi.h>

#include "gipsi/parallel/parallel_session.h"

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  gipsi::ParallelSession session(&argc, &argv);
  const MPI_Comm world = gipsi::ParallelSession::world();
  if (gipsi::ParallelSession::rank(world) != 0) {
    ::testing::TestEventListeners& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  int failed = RUN_ALL_TESTS() != 0 ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, world);
  return failed;
}
