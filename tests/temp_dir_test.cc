// The tests' scratch folders (tests/temp_dir.h) are private to each process, so test programs
// run side by side (ctest -j, two build trees) cannot delete each other's files.

#include "temp_dir.h"

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

namespace gipsi {
namespace {

namespace fs = std::filesystem;

TEST(TestTempDir, TheSameNameInAnotherProcessIsAnotherFolder) {
  const fs::path mine = testing::TempDir("gipsi_plot_", "cli");
  std::ofstream(mine / "keep.txt") << "mine";
  // A second process asks for the same folder, as a second test program would; the child only
  // makes the folder and reports through its exit code (0: a different, fresh, empty folder).
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const fs::path theirs = testing::TempDir("gipsi_plot_", "cli");
    const bool fresh = theirs != mine && fs::is_directory(theirs) && fs::is_empty(theirs);
    std::error_code ignored;
    fs::remove_all(theirs.parent_path(), ignored);  // the child's root (it exits without cleanup)
    _exit(fresh ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  // The first process's file is untouched.
  std::ifstream in(mine / "keep.txt");
  std::string text;
  in >> text;
  EXPECT_EQ(text, "mine");
  EXPECT_EQ(mine.parent_path().filename().string(), "gipsi_test_" + std::to_string(getpid()));
}

TEST(TestTempDir, IsEmptiedWhenAskedForAgainInTheSameProcess) {
  const fs::path dir = testing::TempDir("gipsi_tmp_", "again");
  std::ofstream(dir / "old.txt") << "x";
  EXPECT_EQ(testing::TempDir("gipsi_tmp_", "again"), dir);
  EXPECT_TRUE(fs::is_empty(dir));
  const fs::path named = testing::TestTempDir();
  EXPECT_EQ(named.filename().string(), "TestTempDir.IsEmptiedWhenAskedForAgainInTheSameProcess");
}

}  // namespace
}  // namespace gipsi
