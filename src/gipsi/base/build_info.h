#pragma once
/// @file
/// What this build of GiPSi includes: the optional parts chosen when it was configured (CMake
/// options GIPSI_WITH_GMSH and GIPSI_WITH_OPENIGTLINK, both ON by default). `gipsi --version`
/// and `gipsi types` print them; a scene that needs a part left out is refused at the JSON path
/// that asks for it.

#include <string>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The optional parts of this build. Plain struct.
struct BuildFeatures {
  bool gmsh = false;         ///< Gmsh: the ellipsoid_shell, cylinder_shell, tetrahedralize meshes
  bool openigtlink = false;  ///< OpenIGTLink: networked haptic devices (OpenIGTLink device)
};

/// The parts this build of the libraries has.
[[nodiscard]] BuildFeatures GetBuildFeatures();

/// One line, e.g. "with Gmsh, OpenIGTLink" or "with Gmsh; without OpenIGTLink".
[[nodiscard]] std::string BuildFeatureSummary();

/// The message for a part that is not built in: "<what> needs <part>, which this GiPSi was
/// built without (configure with -D<option>=ON)".
[[nodiscard]] std::string MissingFeature(const std::string& what, const std::string& part,
                                         const std::string& option);

}  // namespace gipsi
GIPSI_EXPORT_END
