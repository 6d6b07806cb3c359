#pragma once
/// @file
/// `ParallelSession`: PETSc (and through it MPI) for the lifetime of a program. GiPSi's
/// distributed objects (gipsi/parallel/) need one; serial runs never create it, so a build with
/// PETSc still runs without `mpirun` and without initialising MPI.

#include <mpi.h>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Initialises PETSc (and MPI, unless the program already has) on construction and finalises
/// what it initialised on destruction; destroy every PETSc object before it. One per process.
/// Not copyable or movable.
class ParallelSession {
 public:
  /// `argc`/`argv` may be null; PETSc reads its options (-ksp_monitor, ...) from them and from
  /// the PETSC_OPTIONS environment variable. Throws std::runtime_error if PETSc fails to start.
  ParallelSession(int* argc, char*** argv);
  ~ParallelSession();
  ParallelSession(const ParallelSession&) = delete;
  ParallelSession& operator=(const ParallelSession&) = delete;

  /// The communicator of every rank (PETSC_COMM_WORLD).
  [[nodiscard]] static MPI_Comm world();
  [[nodiscard]] static int rank(MPI_Comm comm);
  [[nodiscard]] static int size(MPI_Comm comm);

 private:
  bool finalize_ = false;
};

}  // namespace gipsi
GIPSI_EXPORT_END
