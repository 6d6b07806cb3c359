#pragma once
/// @file
/// The package version: the one place it is written. The top-level CMakeLists.txt reads these
/// three numbers for `project(VERSION)`, the installed package's version file
/// (`find_package(gipsi 0.1)`) and `gipsi --version`. Until 1.0, a new minor version may change
/// the C++ API and the plugin interface (GIPSI_PLUGIN_ABI_VERSION in gipsi/core/registry.h).

#define GIPSI_VERSION_MAJOR 0
#define GIPSI_VERSION_MINOR 1
#define GIPSI_VERSION_PATCH 0

#define GIPSI_VERSION_STR2(x) #x
#define GIPSI_VERSION_STR(x) GIPSI_VERSION_STR2(x)
/// "MAJOR.MINOR.PATCH", e.g. "0.1.0".
#define GIPSI_VERSION_STRING             \
  GIPSI_VERSION_STR(GIPSI_VERSION_MAJOR) \
  "." GIPSI_VERSION_STR(GIPSI_VERSION_MINOR) "." GIPSI_VERSION_STR(GIPSI_VERSION_PATCH)
