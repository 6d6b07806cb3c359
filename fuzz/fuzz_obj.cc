// libFuzzer target: the obj mesh reader (ReadObj) on arbitrary bytes.

#include "fuzz/fuzz_util.h"
#include "gipsi/io/obj_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = gipsi::fuzz::WriteInput(data, size, ".obj");
  gipsi::fuzz::ExpectOnlyInputErrors([&] { (void)gipsi::ReadObj(path); });
  return 0;
}
