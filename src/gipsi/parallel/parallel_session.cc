/// @file
/// PETSc and MPI start-up and shut-down.

#include "gipsi/parallel/parallel_session.h"

#include <petscsys.h>

#include "gipsi/parallel/petsc_check.h"

namespace gipsi {

ParallelSession::ParallelSession(int* argc, char*** argv) {
  PetscBool initialized = PETSC_FALSE;
  GIPSI_PETSC(PetscInitialized(&initialized));
  if (initialized) return;
  // PETSc's own error handler prints a traceback and aborts; GiPSi turns error codes into
  // exceptions (petsc_check.h) and reports them itself.
  GIPSI_PETSC(PetscInitialize(argc, argv, nullptr, nullptr));
  GIPSI_PETSC(PetscPushErrorHandler(PetscReturnErrorHandler, nullptr));
  finalize_ = true;
}

ParallelSession::~ParallelSession() {
  if (!finalize_) return;
  PetscPopErrorHandler();
  PetscFinalize();
}

MPI_Comm ParallelSession::world() { return PETSC_COMM_WORLD; }

int ParallelSession::rank(MPI_Comm comm) {
  int r = 0;
  MPI_Comm_rank(comm, &r);
  return r;
}

int ParallelSession::size(MPI_Comm comm) {
  int s = 1;
  MPI_Comm_size(comm, &s);
  return s;
}

}  // namespace gipsi
