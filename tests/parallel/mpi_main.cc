// The MPI test program's main: PETSc (and MPI) for the whole run, GoogleTest's report from rank
// 0 only, the failed assertions of the other ranks (with their rank), one exit code for all
// ranks (any rank's failure fails the program), and a watchdog that turns a stuck test into a
// report of where each rank waits.

#include <execinfo.h>
#include <gtest/gtest.h>
#include <mpi.h>
#include <pthread.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>

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

// The test thread's stack, printed from a signal handler when the watchdog asks for it.
extern "C" void PrintStack(int /*signal*/) {
  void* frames[64];
  const int n = backtrace(frames, 64);
  backtrace_symbols_fd(frames, n, STDERR_FILENO);
}

// A test that runs past the limit (GIPSI_TEST_WATCHDOG_S seconds, 120 by default: the slowest
// test takes about 17 s on 4 ranks over 2 cores) is stuck, most likely in a collective that
// another rank never reaches. Rather than wait for ctest's timeout, which reports nothing,
// every rank prints the test and where it waits (gdb's stacks of all its threads when gdb is
// installed, else the test thread's own) and leaves; mpiexec then ends the others.
class Watchdog final : public ::testing::EmptyTestEventListener {
 public:
  Watchdog(int rank, int limit_s) : rank_(rank), limit_(limit_s), test_thread_(pthread_self()) {
    void* warm[1];
    backtrace(warm, 1);  // loads the unwinder now, not inside the signal handler
    std::signal(SIGUSR2, PrintStack);
    prctl(PR_SET_PTRACER, PR_SET_PTRACER_ANY, 0, 0, 0);  // lets a gdb child read this process
    thread_ = std::thread([this] { Watch(); });
  }
  ~Watchdog() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  Watchdog(const Watchdog&) = delete;
  Watchdog& operator=(const Watchdog&) = delete;

  void OnTestStart(const ::testing::TestInfo& info) override {
    std::lock_guard<std::mutex> lock(mutex_);
    test_ = std::string(info.test_suite_name()) + "." + info.name();
    started_ = std::chrono::steady_clock::now();
  }
  void OnTestEnd(const ::testing::TestInfo& /*info*/) override {
    std::lock_guard<std::mutex> lock(mutex_);
    test_.clear();
  }

 private:
  void Watch() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!stop_) {
      wake_.wait_for(lock, std::chrono::seconds(1));
      if (stop_ || test_.empty() ||
          std::chrono::steady_clock::now() - started_ < std::chrono::seconds(limit_))
        continue;
      std::fprintf(stderr,
                   "[rank %d] %s has run for more than %d s (GIPSI_TEST_WATCHDOG_S): stuck\n",
                   rank_, test_.c_str(), limit_);
      std::fflush(stderr);
      const std::string gdb = "gdb -batch -nx -p " + std::to_string(getpid()) +
                              " -ex 'thread apply all bt 40' 1>&2 2>/dev/null";
      if (access("/usr/bin/gdb", X_OK) != 0 || std::system(gdb.c_str()) != 0) {
        pthread_kill(test_thread_, SIGUSR2);
        std::this_thread::sleep_for(std::chrono::seconds(1));
      }
      std::fflush(stderr);
      std::_Exit(3);
    }
  }

  int rank_;
  int limit_;
  pthread_t test_thread_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::string test_;
  std::chrono::steady_clock::time_point started_;
  std::thread thread_;
};

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  gipsi::ParallelSession session(&argc, &argv);
  const MPI_Comm world = gipsi::ParallelSession::world();
  const int rank = gipsi::ParallelSession::rank(world);
  ::testing::TestEventListeners& listeners = ::testing::UnitTest::GetInstance()->listeners();
  if (rank != 0) {
    delete listeners.Release(listeners.default_result_printer());
    listeners.Append(new RankFailurePrinter(rank));
  }
  const char* limit = std::getenv("GIPSI_TEST_WATCHDOG_S");
  const int limit_s = limit != nullptr ? std::atoi(limit) : 120;
  if (limit_s > 0) listeners.Append(new Watchdog(rank, limit_s));
  int failed = RUN_ALL_TESTS() != 0 ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, world);
  return failed;
}
