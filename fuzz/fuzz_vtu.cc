// libFuzzer target: the vtu mesh reader (ReadVtu, and one block of it) on arbitrary bytes.

#include "fuzz/fuzz_util.h"
#include "gipsi/io/vtu_block_reader.h"
#include "gipsi/io/vtu_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = gipsi::fuzz::WriteInput(data, size, ".vtu");
  gipsi::fuzz::ExpectOnlyInputErrors([&] { (void)gipsi::ReadVtu(path); });
  // One process's block of three, streamed (what a distributed run reads).
  gipsi::fuzz::ExpectOnlyInputErrors([&] { (void)gipsi::ReadVtuBlock(path, 1, 3); });
  return 0;
}
