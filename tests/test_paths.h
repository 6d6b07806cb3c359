#pragma once
/// @file
/// Where the tests find the checkout, the shared sample data and the build tree. The absolute
/// paths are compiled into one source file (test_paths.cc) rather than passed to every test
/// file as definitions, so that test objects compiled in one checkout are reused from ccache
/// by a clean checkout in another folder (CI).

namespace gipsi::test {
/// The source checkout (the folder holding scenes/, docs/ and tests/).
const char* SourceDir();
/// ../shared/data beside the checkout: the real sample meshes.
const char* SharedDataDir();
/// The CMake build folder (bin/gipsi is below it).
const char* BinaryDir();
}  // namespace gipsi::test

#define GIPSI_SOURCE_DIR (::gipsi::test::SourceDir())
#define GIPSI_SHARED_DATA_DIR (::gipsi::test::SharedDataDir())
#define GIPSI_BINARY_DIR (::gipsi::test::BinaryDir())
