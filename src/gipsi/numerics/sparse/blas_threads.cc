#include "gipsi/numerics/sparse/blas_threads.h"

#include <dlfcn.h>

#include <mutex>
#include <string>

namespace gipsi {

BlasThreadsResult UseSingleThreadedBlas(const SymbolLookup& lookup) {
  BlasThreadsResult result;
  using SetThreads = void (*)(int);
  if (void* f = lookup("openblas_set_num_threads")) {
    reinterpret_cast<SetThreads>(f)(1);
    result.openblas = true;
  }
  if (void* f = lookup("bli_thread_set_num_threads")) {
    reinterpret_cast<SetThreads>(f)(1);
    result.blis = true;
  }
  return result;
}

void UseSingleThreadedBlasOnce() {
  static std::once_flag once;
  std::call_once(once, [] {
    UseSingleThreadedBlas(
        [](std::string_view name) { return dlsym(RTLD_DEFAULT, std::string(name).c_str()); });
  });
}

}  // namespace gipsi
