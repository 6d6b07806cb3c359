#pragma once
/// @file
/// The result of advancing an object or firing a connector. Nothing inside a step throws or
/// allocates: trouble is reported as a status that the kernel turns into a diagnostic and a
/// policy (today: stop the run, keeping everything already written).

#include <cstdint>

namespace gipsi {

/// Trivially copyable. `what` points to a string literal (static storage), so making a status
/// never allocates; `item` and `value` locate the problem (e.g. node 17, value NaN).
struct StepStatus {
  enum class Code : std::uint8_t {
    kOk,        ///< advanced normally
    kDiverged,  ///< the state became non-finite or exceeded a model bound
    kFailed,    ///< a solver or model could not complete the step
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
};

}  // namespace gipsi
