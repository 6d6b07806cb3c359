// libFuzzer target: the gmsh mesh reader (ReadGmsh, and one block of it) on arbitrary bytes.

#include "fuzz/fuzz_util.h"
#include "gipsi/io/gmsh_block_reader.h"
#include "gipsi/io/gmsh_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = gipsi::fuzz::WriteInput(data, size, ".msh");
  gipsi::fuzz::ExpectOnlyInputErrors([&] { (void)gipsi::ReadGmsh(path); });
  // One process's block of three, streamed (what a distributed run reads).
  gipsi::fuzz::ExpectOnlyInputErrors([&] { (void)gipsi::ReadGmshBlock(path, 1, 3); });
  return 0;
}
