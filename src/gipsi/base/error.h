#pragma once
/// @file
/// Errors and checks. Three tiers (see STYLE.md):
///  - `GIPSI_DCHECK`: debug-only invariant checks, compiled out in release builds;
///  - `GIPSI_CHECK`: always-on checks of programmer errors; they abort with a message;
///  - `InputError`: an exception for bad user input (scene files, meshes, parameters), whose
///    message names the file, the location (JSON path or line) and what was expected.
/// Nothing inside a simulation step throws: steps return a `StepStatus` instead.

#include <stdexcept>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Bad user input: a malformed file, an unknown type name, an out-of-range parameter.
/// The message is complete and meant for the user, e.g.
/// `scene.json: objects.sheet.stiffness: expected a positive number, got "abc"`.
/// Copyable and movable (it is an exception).
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

/// Builds an InputError message of the form `FILE: LOCATION: WHAT` (empty parts are skipped).
std::string FormatInputError(std::string_view file, std::string_view location,
                             std::string_view what);

/// Throws InputError(FormatInputError(file, location, what)).
[[noreturn]] void ThrowInputError(std::string_view file, std::string_view location,
                                  std::string_view what);

namespace internal {
[[noreturn]] void AbortWithMessage(const char* condition, const char* file, int line,
                                   const std::string& message);
}  // namespace internal

}  // namespace gipsi
GIPSI_EXPORT_END

/// Always-on check of a programmer error (a violated precondition of a public API). Aborts.
#define GIPSI_CHECK(cond, ...)                                            \
  do {                                                                    \
    if (!(cond)) [[unlikely]]                                             \
      ::gipsi::internal::AbortWithMessage(#cond, __FILE__, __LINE__,      \
                                          ::fmt::format("" __VA_ARGS__)); \
  } while (false)

#ifdef NDEBUG
#define GIPSI_DCHECK(cond, ...) \
  do {                          \
  } while (false)
#else
/// Debug-only invariant check.
#define GIPSI_DCHECK(cond, ...) GIPSI_CHECK(cond __VA_OPT__(, ) __VA_ARGS__)
#endif
