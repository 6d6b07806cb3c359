#include "gipsi/numerics/simd.h"

#include <algorithm>
#include <atomic>

namespace gipsi {
namespace {

SimdKernels Supported() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  // libgcc's and compiler-rt's feature tests report AVX only when the OS saves the YMM state
  // (OSXSAVE and XCR0), so a kernel that does not is not offered AVX.
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx")) return SimdKernels::kAvx;
#endif
  return SimdKernels::kGeneric;
}

std::atomic<SimdKernels>& Limit() {
  static std::atomic<SimdKernels> limit{SimdKernels::kAvx};
  return limit;
}

}  // namespace

SimdKernels ActiveSimdKernels() {
  static const SimdKernels supported = Supported();
  return std::min(supported, Limit().load(std::memory_order_relaxed));
}

SimdKernels LimitSimdKernels(SimdKernels limit) {
  return Limit().exchange(limit, std::memory_order_relaxed);
}

const char* SimdKernelsName(SimdKernels kernels) {
  return kernels == SimdKernels::kAvx ? "avx" : "generic";
}

}  // namespace gipsi
