#pragma once
/// @file
/// GIPSI_EXPORT, the one export macro. The layer libraries are built with hidden symbols
/// (`-fvisibility=hidden`): what only a .cc file declares (helpers, and the instantiations of
/// Eigen, fmt, spdlog and nlohmann templates) stays inside its library. Every public header
/// opens its namespace as `namespace GIPSI_EXPORT gipsi {`, so everything the installed headers
/// declare, classes with their vtables and type information included, is exported: the headers
/// are the ABI. A program or plugin built against the package needs nothing of this.

#define GIPSI_EXPORT [[gnu::visibility("default")]]
