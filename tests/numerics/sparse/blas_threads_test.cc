// The BLAS under CHOLMOD is asked for one thread at run time, whichever BLAS the system's
// libblas.so.3 alternative selects, so the install script never changes that system setting.

#include <dlfcn.h>

#include <map>
#include <string>

#include <gtest/gtest.h>

#include "gipsi/numerics/sparse/blas_threads.h"
#include "gipsi/numerics/sparse/linear_solver.h"

namespace gipsi {
namespace {

int g_openblas_threads = 0;
int g_blis_threads = 0;
void FakeOpenBlasSet(int n) { g_openblas_threads = n; }
void FakeBlisSet(int n) { g_blis_threads = n; }

TEST(BlasThreads, EveryRecognisedBlasIsAskedForOneThread) {
  g_openblas_threads = g_blis_threads = 8;
  const std::map<std::string, void*> symbols = {
      {"openblas_set_num_threads", reinterpret_cast<void*>(&FakeOpenBlasSet)},
      {"bli_thread_set_num_threads", reinterpret_cast<void*>(&FakeBlisSet)}};
  const BlasThreadsResult result = UseSingleThreadedBlas([&](std::string_view name) -> void* {
    const auto it = symbols.find(std::string(name));
    return it == symbols.end() ? nullptr : it->second;
  });
  EXPECT_TRUE(result.openblas);
  EXPECT_TRUE(result.blis);
  EXPECT_EQ(g_openblas_threads, 1);
  EXPECT_EQ(g_blis_threads, 1);
}

TEST(BlasThreads, ABlasWithoutThreadControlIsLeftAlone) {
  const BlasThreadsResult result = UseSingleThreadedBlas([](std::string_view) { return nullptr; });
  EXPECT_FALSE(result.openblas);
  EXPECT_FALSE(result.blis);
}

// The process's own BLAS: once a CHOLMOD solver exists, an OpenBLAS (serial, pthread or OpenMP
// build, whichever the alternative selects) reports one thread.
TEST(BlasThreads, ACholmodSolverLeavesTheLoadedOpenBlasOnOneThread) {
  LinearSolverOptions options;
  options.type = "cholmod";
  const auto solver = MakeLinearSolver(options);
  using GetThreads = int (*)();
  void* get = dlsym(RTLD_DEFAULT, "openblas_get_num_threads");
  if (get == nullptr) GTEST_SKIP() << "the loaded BLAS is not OpenBLAS (nothing to limit)";
  EXPECT_EQ(reinterpret_cast<GetThreads>(get)(), 1);
}

}  // namespace
}  // namespace gipsi
