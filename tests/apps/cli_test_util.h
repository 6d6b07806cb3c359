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

/// Runs `gipsi ARGS` (the binary of this build tree) and captures its output. `prefix` is shell
/// text run before it in the same shell (e.g. `ulimit -f 1;`).
inline Result Gipsi(const std::string& args, const std::string& prefix = "") {
  const std::string command =
      prefix + " exec " + std::string(GIPSI_BINARY_DIR) + "/bin/gipsi " + args + " 2>&1";
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

/// Runs `gipsi ARGS` with every file it writes limited to 512 bytes (`ulimit -f 1`, SIGXFSZ
/// ignored): a write past that fails with EFBIG ("File too large") as one on a full disk fails
/// with ENOSPC, without mounting anything or changing the system.
inline Result GipsiWithTinyFiles(const std::string& args) {
  return Gipsi(args, "ulimit -f 1; trap '' XFSZ;");
}

}  // namespace gipsi::testing
