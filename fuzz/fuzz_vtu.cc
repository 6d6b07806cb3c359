// libFuzzer target: the vtu mesh reader (ReadVtu) on arbitrary bytes.

#include "fuzz/fuzz_util.h"
#include "gipsi/io/vtu_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = gipsi::fuzz::WriteInput(data, size, ".vtu");
  gipsi::fuzz::ExpectOnlyInputErrors([&] { (void)gipsi::ReadVtu(path); });
  return 0;
}
