// libFuzzer target: the vtk mesh reader (ReadVtkLegacy, and one block of it) on arbitrary bytes.

#include "fuzz/fuzz_util.h"
#include "gipsi/io/vtk_legacy_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = gipsi::fuzz::WriteInput(data, size, ".vtk");
  gipsi::fuzz::ExpectOnlyInputErrors([&] { (void)gipsi::ReadVtkLegacy(path); });
  // One process's block of three, streamed (what a distributed run reads).
  gipsi::fuzz::ExpectOnlyInputErrors([&] { (void)gipsi::ReadVtkLegacyBlock(path, 1, 3); });
  return 0;
}
