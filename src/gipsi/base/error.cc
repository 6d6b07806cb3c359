#include "gipsi/base/error.h"

#include <cstdio>
#include <cstdlib>

namespace gipsi {

std::string FormatInputError(std::string_view file, std::string_view location,
                             std::string_view what) {
  std::string out;
  if (!file.empty()) out += fmt::format("{}: ", file);
  if (!location.empty()) out += fmt::format("{}: ", location);
  out += what;
  return out;
}

void ThrowInputError(std::string_view file, std::string_view location, std::string_view what) {
  throw InputError(FormatInputError(file, location, what));
}

namespace internal {
void AbortWithMessage(const char* condition, const char* file, int line,
                      const std::string& message) {
  std::fprintf(stderr, "gipsi: internal check failed: %s at %s:%d%s%s\n", condition, file, line,
               message.empty() ? "" : ": ", message.c_str());
  std::abort();
}
}  // namespace internal

}  // namespace gipsi
