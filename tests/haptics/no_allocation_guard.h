#pragma once
// A guard that fails the test if the current thread calls global operator new while it lives.
// The counting replacement of operator new is defined once, in haptics_test.cc; under
// AddressSanitizer it is left out (ASan's own operator new must stay) and nothing is counted.

#include <gtest/gtest.h>

namespace gipsi::testing {

extern thread_local bool g_counting_allocations;
extern thread_local long g_allocations;

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kCountsAllocations = false;
#else
inline constexpr bool kCountsAllocations = true;
#endif

/// Fails the test if the current thread allocates while it lives.
class NoAllocationGuard {
 public:
  // Without counting (sanitizer builds) the thread-local flags are left alone.
  NoAllocationGuard() {
    if constexpr (kCountsAllocations) {
      g_allocations = 0;
      g_counting_allocations = true;
    }
  }
  ~NoAllocationGuard() {
    if constexpr (kCountsAllocations) {
      g_counting_allocations = false;
      EXPECT_EQ(g_allocations, 0) << "heap allocations inside a real-time section";
    }
  }
  NoAllocationGuard(const NoAllocationGuard&) = delete;
  NoAllocationGuard& operator=(const NoAllocationGuard&) = delete;
};

}  // namespace gipsi::testing
