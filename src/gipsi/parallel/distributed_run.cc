/// @file
/// The distributed run the `gipsi` tool loads with dlopen.

#include "gipsi/parallel/distributed_run.h"

#include <mpi.h>

#include <chrono>
#include <thread>
#include <utility>

#include "gipsi/parallel/distributed_types.h"
#include "gipsi/parallel/parallel_session.h"
#include "gipsi/parallel/whole_domain_view.h"

namespace gipsi {
namespace {

class PetscRun final : public DistributedRun {
 public:
  PetscRun() : session_(nullptr, nullptr) { MPI_Comm_dup(world(), &failures_); }
  ~PetscRun() override { MPI_Comm_free(&failures_); }
  PetscRun(const PetscRun&) = delete;
  PetscRun& operator=(const PetscRun&) = delete;
  [[nodiscard]] int rank() const override { return ParallelSession::rank(world()); }
  [[nodiscard]] int size() const override { return ParallelSession::size(world()); }
  void RegisterTypes(TypeRegistry& registry) const override {
    RegisterDistributedTypes(registry, world(), split_);
  }
  [[nodiscard]] std::vector<std::string> split_objects() const override { return *split_; }
  void SetCheckpointFiles(std::vector<std::filesystem::path> files) const override {
    WholeDomainView::SetCheckpointFiles(std::move(files));
  }
  void Barrier() const override { MPI_Barrier(world()); }
  [[noreturn]] void Abort(int code) const override {
    MPI_Abort(world(), code);
    std::abort();  // MPI_Abort does not return
  }
  [[nodiscard]] std::optional<std::string> AgreeOnFailure(const std::string& message,
                                                          double seconds) const override {
    MPI_Request arrived = MPI_REQUEST_NULL;
    MPI_Ibarrier(failures_, &arrived);
    const double start = MPI_Wtime();
    for (int done = 0; done == 0;) {
      MPI_Test(&arrived, &done, MPI_STATUS_IGNORE);
      if (done == 0 && MPI_Wtime() - start > seconds) return std::nullopt;  // Abort follows
      if (done == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    // Every rank failed and is here: rank 0's message to all.
    int length = static_cast<int>(message.size());
    MPI_Bcast(&length, 1, MPI_INT, 0, failures_);
    std::string first = rank() == 0 ? message : std::string(static_cast<std::size_t>(length), ' ');
    MPI_Bcast(first.data(), length, MPI_CHAR, 0, failures_);
    return first;
  }

 private:
  static MPI_Comm world() { return ParallelSession::world(); }
  ParallelSession session_;
  MPI_Comm failures_ = MPI_COMM_NULL;  // AgreeOnFailure's alone
  std::shared_ptr<std::vector<std::string>> split_ = std::make_shared<std::vector<std::string>>();
};

}  // namespace
}  // namespace gipsi

extern "C" gipsi::DistributedRun* gipsi_parallel_start() { return new gipsi::PetscRun(); }
