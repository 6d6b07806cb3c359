#pragma once
/// @file
/// `StopToken`: a read-only view of a run's stop request (the kernel's flag, set by
/// `Kernel::RequestStop` from a signal handler or another thread), handed down to the loops
/// that can run long inside one step — Newton iterations, load increments, bisections — so a
/// stop request is honoured within one iteration instead of after the macro step.

#include <atomic>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Trivially copyable; does not own the flag, which must outlive every copy (the kernel's).
/// A default-constructed token never requests a stop.
class StopToken {
 public:
  StopToken() = default;
  explicit StopToken(const std::atomic<bool>* flag) : flag_(flag) {}
  /// Whether a stop was requested. Lock-free and allocation-free: poll it in inner loops.
  [[nodiscard]] bool stop_requested() const {
    return flag_ != nullptr && flag_->load(std::memory_order_relaxed);
  }

 private:
  const std::atomic<bool>* flag_ = nullptr;
};

}  // namespace gipsi
GIPSI_EXPORT_END
