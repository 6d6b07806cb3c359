// A plugin that claims another ABI: the next release line (0.2 for 0.1), or, with
// GIPSI_TEST_LEGACY_ABI, a bare interface number as gipsi returned before the package version
// was part of it. The loader must refuse it before registering anything: its registrar aborts.

#include <cstdlib>

#include "gipsi/core/registry.h"

extern "C" int gipsi_plugin_abi_version() {
#ifdef GIPSI_TEST_LEGACY_ABI
  return 10;
#else
  return GIPSI_PLUGIN_ABI_VERSION + 1000;  // the same interface in the next minor version
#endif
}

extern "C" void gipsi_register_plugin(gipsi::TypeRegistry& /*registry*/) { std::abort(); }
