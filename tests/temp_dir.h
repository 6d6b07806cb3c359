#pragma once
/// @file
/// Scratch folders for tests. ctest runs test programs side by side (and one test may run in two
/// build trees at once), so a fixed folder such as /tmp/gipsi_plot_cli would be deleted or
/// overwritten by another process under a running test: every folder here lives under
/// `<system temp>/gipsi_test_<pid>/`, private to the process. The process's folder is removed
/// when it exits if every test passed, and kept for inspection otherwise.

#include <filesystem>
#include <string>

namespace gipsi::testing {

/// This process's scratch root, `<system temp>/gipsi_test_<pid>` (created).
std::filesystem::path ProcessTempRoot();

/// An empty folder `<ProcessTempRoot()>/<prefix><name>` (emptied if it exists).
std::filesystem::path TempDir(const std::string& prefix, const std::string& name);

/// An empty folder named after the running test, `<ProcessTempRoot()>/<Suite>.<Test>`.
std::filesystem::path TestTempDir();

}  // namespace gipsi::testing
