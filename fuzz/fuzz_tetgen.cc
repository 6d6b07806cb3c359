// libFuzzer target: the TetGen reader on arbitrary .node and .ele files (the input is split at
// the first "@@" into the two files; without one, the .ele file is empty).

#include <string_view>

#include "fuzz/fuzz_util.h"
#include "gipsi/io/tetgen_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const std::size_t split = text.find("@@");
  const std::string_view node = text.substr(0, split);
  const std::string_view ele =
      split == std::string_view::npos ? std::string_view() : text.substr(split + 2);
  const auto node_path = gipsi::fuzz::WriteInput(reinterpret_cast<const std::uint8_t*>(node.data()),
                                                 node.size(), ".node");
  (void)gipsi::fuzz::WriteInput(reinterpret_cast<const std::uint8_t*>(ele.data()), ele.size(),
                                ".ele");
  gipsi::fuzz::ExpectOnlyInputErrors([&] { (void)gipsi::ReadTetGen(node_path); });
  return 0;
}
