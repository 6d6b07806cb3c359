// libFuzzer target: the gmsh mesh reader (ReadGmsh) on arbitrary bytes.

#include "fuzz/fuzz_util.h"
#include "gipsi/io/gmsh_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = gipsi::fuzz::WriteInput(data, size, ".msh");
  gipsi::fuzz::ExpectOnlyInputErrors([&] { (void)gipsi::ReadGmsh(path); });
  return 0;
}
