#include "gipsi/base/build_info.h"

#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

// Set for this file alone by src/CMakeLists.txt from the CMake options.
#ifndef GIPSI_WITH_GMSH
#error "GIPSI_WITH_GMSH must be defined (0 or 1) by the build"
#endif
#ifndef GIPSI_WITH_OPENIGTLINK
#error "GIPSI_WITH_OPENIGTLINK must be defined (0 or 1) by the build"
#endif

namespace gipsi {

BuildFeatures GetBuildFeatures() {
  return BuildFeatures{.gmsh = GIPSI_WITH_GMSH != 0, .openigtlink = GIPSI_WITH_OPENIGTLINK != 0};
}

std::string BuildFeatureSummary() {
  const BuildFeatures f = GetBuildFeatures();
  std::vector<std::string> with, without;
  (f.gmsh ? with : without).push_back("Gmsh");
  (f.openigtlink ? with : without).push_back("OpenIGTLink");
  std::string summary;
  if (!with.empty()) summary = fmt::format("with {}", fmt::join(with, ", "));
  if (!without.empty())
    summary += fmt::format("{}without {}", summary.empty() ? "" : "; ", fmt::join(without, ", "));
  return summary;
}

std::string MissingFeature(const std::string& what, const std::string& part,
                           const std::string& option) {
  return fmt::format("{} needs {}, which this GiPSi was built without (configure with -D{}=ON)",
                     what, part, option);
}

}  // namespace gipsi
