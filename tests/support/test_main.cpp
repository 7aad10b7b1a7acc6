// main() of every test binary: gives the process a temporary directory of its own. ctest runs the
// cases of one binary as parallel processes, and tests write files under ::testing::TempDir() or
// std::filesystem::temp_directory_path(); one fresh directory per process (TEST_TMPDIR and TMPDIR point
// at it) keeps parallel cases from writing over each other's files. It is removed at exit.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <string>
#include <system_error>

int main(int argc, char** argv) {
  const char* base = std::getenv("TMPDIR");
  std::string templ = std::string(base && *base ? base : "/tmp") + "/uavsim-test-XXXXXX";
  const char* dir = mkdtemp(templ.data());
  if (dir != nullptr) {
    setenv("TEST_TMPDIR", dir, 1);
    setenv("TMPDIR", dir, 1);
  }
  ::testing::InitGoogleTest(&argc, argv);
  const int result = RUN_ALL_TESTS();
  if (dir != nullptr) {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
  return result;
}
