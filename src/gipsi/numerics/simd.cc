#include "gipsi/numerics/simd.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <string_view>

#include "gipsi/base/log.h"

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

// GIPSI_SIMD=generic in the environment limits the kernels from the start (to compare
// machines or speeds; the bits are the same either way).
SimdKernels LimitFromEnvironment() {
  const char* value = std::getenv("GIPSI_SIMD");
  if (!value || !*value) return SimdKernels::kAvx;
  const std::string_view text(value);
  if (text == "generic") return SimdKernels::kGeneric;
  if (text != "avx")
    Log().warn("GIPSI_SIMD='{}' ignored: expected 'generic' or 'avx' (the vector kernels)", text);
  return SimdKernels::kAvx;
}

std::atomic<SimdKernels>& Limit() {
  static std::atomic<SimdKernels> limit{LimitFromEnvironment()};
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
