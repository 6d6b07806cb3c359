#pragma once
/// @file
/// The result of advancing an object or firing a connector. Nothing inside a step throws or
/// allocates: trouble is reported as a status that the kernel turns into a diagnostic and a
/// policy (today: stop the run, keeping everything already written).

#include <cstdint>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Trivially copyable. `what` points to a string literal (static storage), so making a status
/// never allocates; `item` and `value` locate the problem (e.g. node 17, value NaN).
struct StepStatus {
  enum class Code : std::uint8_t {
    kOk,        ///< advanced normally
    kDiverged,  ///< the state became non-finite or exceeded a model bound
    kFailed,    ///< a solver or model could not complete the step
    /// A stop was requested (SimObject::stop_token) while the step ran: the object abandoned
    /// it and is back at the state it had at the start of the step. Not a failure: the kernel
    /// ends the run as "stopped on request".
    kStopped,
  };
  Code code = Code::kOk;
  const char* what = "";
  std::int64_t item = -1;  ///< node/element/vertex index involved, or -1
  double value = 0;        ///< the offending value, if any

  [[nodiscard]] bool ok() const { return code == Code::kOk; }
  static constexpr StepStatus Ok() { return {}; }
  static constexpr StepStatus Diverged(const char* what, std::int64_t item = -1, double value = 0) {
    return {Code::kDiverged, what, item, value};
  }
  static constexpr StepStatus Failed(const char* what, std::int64_t item = -1, double value = 0) {
    return {Code::kFailed, what, item, value};
  }
  static constexpr StepStatus Stopped(const char* what = "stopped on request") {
    return {Code::kStopped, what, -1, 0};
  }
};

}  // namespace gipsi
GIPSI_EXPORT_END
