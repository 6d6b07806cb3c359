// The only test source compiled with the checkout's absolute paths (see test_paths.h).
#include "test_paths.h"

namespace gipsi::test {
const char* SourceDir() { return GIPSI_TEST_SOURCE_DIR; }
const char* SharedDataDir() { return GIPSI_TEST_SHARED_DATA_DIR; }
const char* BinaryDir() { return GIPSI_TEST_BINARY_DIR; }
}  // namespace gipsi::test
