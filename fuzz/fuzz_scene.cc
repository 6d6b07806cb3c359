// libFuzzer target: the scene loader on arbitrary text. Inputs naming plugins are skipped
// (loading an arbitrary shared library is the plugin mechanism's purpose, not a parser bug).

#include <string>

#include "fuzz/fuzz_util.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  if (text.find("plugins") != std::string::npos) return 0;
  static gipsi::TypeRegistry* registry = [] {
    auto* r = new gipsi::TypeRegistry;
    gipsi::RegisterBuiltins(*r);
    return r;
  }();
  gipsi::fuzz::ExpectOnlyInputErrors(
      [&] { (void)gipsi::LoadSceneFromString(text, "fuzz.json", "/nonexistent", *registry); });
  return 0;
}
