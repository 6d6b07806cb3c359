#pragma once
// Running the real `gipsi` binary from end-to-end tests.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include "temp_dir.h"
#include "test_paths.h"

namespace gipsi::testing {

/// Exit code and combined stdout + stderr of one `gipsi` invocation.
struct Result {
  int code = -1;
  std::string output;
};

/// Runs `gipsi ARGS` (the binary of this build tree) and captures its output.
inline Result Gipsi(const std::string& args) {
  const std::string command = std::string(GIPSI_BINARY_DIR) + "/bin/gipsi " + args + " 2>&1";
  Result result;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buffer{};
  while (std::size_t n = fread(buffer.data(), 1, buffer.size(), pipe))
    result.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  result.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

}  // namespace gipsi::testing
