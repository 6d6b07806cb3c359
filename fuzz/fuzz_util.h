#pragma once
// Shared by the fuzz targets: the input written to a per-process file with the reader's
// extension (the readers take paths), and the contract every target checks — bad input may only
// raise gipsi::InputError; any other exception, crash, sanitizer report, hang (libFuzzer
// -timeout) or unbounded allocation (-rss_limit_mb, -malloc_limit_mb) is a finding.

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "gipsi/base/error.h"

// libgmsh 4.8 leaks a little per meshing (see the test suite); not ours to fix.
extern "C" __attribute__((weak)) const char* __lsan_default_suppressions() {
  return "leak:libgmsh.so\n";
}

// See apps/gipsi_main.cc: libfreeimage (through Gmsh) mismatches new and free at exit.
extern "C" __attribute__((weak)) const char* __asan_default_options() {
  return "alloc_dealloc_mismatch=0";
}

namespace gipsi::fuzz {

/// Writes `data` to a file named "input<extension>" in a per-process folder under /dev/shm
/// (or the temp directory) and returns its path.
inline std::filesystem::path WriteInput(const std::uint8_t* data, std::size_t size,
                                        const std::string& extension) {
  static const std::filesystem::path dir = [] {
    std::filesystem::path base = std::filesystem::exists("/dev/shm")
                                     ? std::filesystem::path("/dev/shm")
                                     : std::filesystem::temp_directory_path();
    auto d = base / ("gipsi_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  const auto path = dir / ("input" + extension);
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

/// Runs `fn`; InputError is the expected outcome for bad input, anything else aborts.
template <class Fn>
void ExpectOnlyInputErrors(Fn&& fn) {
  try {
    fn();
  } catch (const InputError&) {
  } catch (const std::exception& e) {
    std::fprintf(stderr, "finding: an exception other than InputError escaped: %s\n", e.what());
    std::abort();
  }
}

}  // namespace gipsi::fuzz
