#pragma once
/// @file
/// GIPSI_EXPORT_BEGIN / GIPSI_EXPORT_END, the one export mechanism. The layer libraries are
/// built with hidden symbols (`-fvisibility=hidden`): what only a .cc file declares (helpers,
/// and the instantiations of Eigen, fmt and nlohmann templates) stays inside its library. Every
/// public header wraps its namespace in the pair, so everything the installed headers declare,
/// classes with their vtables and type information included, is exported: the headers are the
/// ABI. A program or plugin built against the package needs nothing of this.
///
/// A pragma, not an attribute on the namespace: GCC honours `namespace [[gnu::visibility]]`
/// but Clang ignores it for functions defined outside that namespace block, and the sanitizer
/// and fuzzing builds use Clang.

#define GIPSI_EXPORT_BEGIN _Pragma("GCC visibility push(default)")
#define GIPSI_EXPORT_END _Pragma("GCC visibility pop")
