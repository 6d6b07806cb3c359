#include "temp_dir.h"

#include <unistd.h>

#include <gtest/gtest.h>

namespace gipsi::testing {
namespace {

/// Removes the process's scratch root at exit when every test passed. A function-local static
/// made on first use, i.e. after gtest's UnitTest singleton, so destroyed before it.
struct RootCleanup {
  std::filesystem::path root;
  ~RootCleanup() {
    if (!::testing::UnitTest::GetInstance()->Passed()) return;
    std::error_code ignored;
    std::filesystem::remove_all(root, ignored);
  }
};

}  // namespace

std::filesystem::path ProcessTempRoot() {
  static RootCleanup cleanup{std::filesystem::temp_directory_path() /
                             ("gipsi_test_" + std::to_string(getpid()))};
  // A forked child has another pid than the process that made the static.
  const std::filesystem::path root =
      std::filesystem::temp_directory_path() / ("gipsi_test_" + std::to_string(getpid()));
  std::filesystem::create_directories(root);
  return root;
}

std::filesystem::path TempDir(const std::string& prefix, const std::string& name) {
  const std::filesystem::path dir = ProcessTempRoot() / (prefix + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::filesystem::path TestTempDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return TempDir("", info ? std::string(info->test_suite_name()) + "." + info->name()
                          : std::string("no_test"));
}

}  // namespace gipsi::testing
