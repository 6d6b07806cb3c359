// libFuzzer target: the stl mesh reader (ReadStl) on arbitrary bytes.

#include "fuzz/fuzz_util.h"
#include "gipsi/io/stl_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = gipsi::fuzz::WriteInput(data, size, ".stl");
  gipsi::fuzz::ExpectOnlyInputErrors([&] { (void)gipsi::ReadStl(path); });
  return 0;
}
