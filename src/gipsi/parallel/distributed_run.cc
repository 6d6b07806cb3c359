/// @file
/// The distributed run the `gipsi` tool loads with dlopen.

#include "gipsi/parallel/distributed_run.h"

#include <mpi.h>

#include "gipsi/parallel/distributed_types.h"
#include "gipsi/parallel/parallel_session.h"

namespace gipsi {
namespace {

class PetscRun final : public DistributedRun {
 public:
  PetscRun() : session_(nullptr, nullptr) {}
  [[nodiscard]] int rank() const override { return ParallelSession::rank(world()); }
  [[nodiscard]] int size() const override { return ParallelSession::size(world()); }
  void RegisterTypes(TypeRegistry& registry) const override {
    RegisterDistributedTypes(registry, world());
  }
  [[nodiscard]] std::vector<std::string> type_names() const override {
    return DistributedTypeNames();
  }
  void Barrier() const override { MPI_Barrier(world()); }
  [[noreturn]] void Abort(int code) const override {
    MPI_Abort(world(), code);
    std::abort();  // MPI_Abort does not return
  }

 private:
  static MPI_Comm world() { return ParallelSession::world(); }
  ParallelSession session_;
};

}  // namespace
}  // namespace gipsi

extern "C" gipsi::DistributedRun* gipsi_parallel_start() { return new gipsi::PetscRun(); }
