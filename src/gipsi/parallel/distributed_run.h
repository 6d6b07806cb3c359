#pragma once
/// @file
/// The `gipsi` tool's way into distributed runs without linking MPI: under an MPI launcher it
/// loads libgipsi_parallel with dlopen and calls `gipsi_parallel_start`, so serial runs of
/// every build neither load nor start MPI (linking PETSc made every start of the tool 0.12 s
/// and 22 MB heavier). This header names no MPI type.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/registry.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// PETSc and MPI for one distributed run, and what the tool needs of them. Destroying it
/// finalises PETSc and MPI (destroy every object of the run first). Not copyable.
class DistributedRun {
 public:
  virtual ~DistributedRun() = default;
  [[nodiscard]] virtual int rank() const = 0;
  [[nodiscard]] virtual int size() const = 0;
  /// Replaces the factories of the distributed types (distributed_types.h).
  virtual void RegisterTypes(TypeRegistry& registry) const = 0;
  /// The objects the replaced factories have split over the ranks so far, as "name (Type)"
  /// (a FemSolid with the ODE contract's implicit integrator, for one, still runs whole on every
  /// rank).
  [[nodiscard]] virtual std::vector<std::string> split_objects() const = 0;
  /// The files of the checkpoint a run resumes from, every rank's, rank 0's first: a split
  /// object restores from them on another rank count (WholeDomainView::SetCheckpointFiles).
  virtual void SetCheckpointFiles(std::vector<std::filesystem::path> files) const = 0;
  /// Waits until every rank has called it.
  virtual void Barrier() const = 0;
  /// Ends every rank with `code` (MPI_Abort): for a failure one rank meets alone.
  [[noreturn]] virtual void Abort(int code) const = 0;
  /// After an error on this rank (`message`): waits up to `seconds` for every rank to report
  /// one too (on a communicator of its own, so no collective of the run can match it), and
  /// returns rank 0's message if they all did (every rank read the same bad scene: the caller
  /// prints it once and exits normally), or nothing if some rank did not (it is waiting in the
  /// run: the caller aborts).
  [[nodiscard]] virtual std::optional<std::string> AgreeOnFailure(const std::string& message,
                                                                  double seconds) const = 0;
};

/// The name dlopen looks gipsi_parallel_start up by.
inline constexpr const char* kParallelStartSymbol = "gipsi_parallel_start";
/// Its type.
using ParallelStartFunction = DistributedRun* (*)();

}  // namespace gipsi

/// Starts PETSc and MPI (options from the PETSC_OPTIONS environment variable) and returns the
/// run (owned by the caller). Throws std::runtime_error if they fail to start.
extern "C" gipsi::DistributedRun* gipsi_parallel_start();
GIPSI_EXPORT_END
