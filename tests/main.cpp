// The test programs' entry point. ctest runs every test as its own process, many at once, and
// several tests write files of the same name; so each process gets its own temporary folder
// (TEST_TMPDIR for ::testing::TempDir(), TMPDIR for std::filesystem::temp_directory_path()
// and the knitsim processes the tests start), removed at the end unless a test failed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path dir = fs::temp_directory_path(ec) / ("knitsim-tests-" + std::to_string(getpid()));
  fs::remove_all(dir, ec);
  const bool own = !ec && fs::create_directories(dir, ec) && !ec;
  if (own) {
    setenv("TEST_TMPDIR", dir.c_str(), 1);
    setenv("TMPDIR", dir.c_str(), 1);
  }
  ::testing::InitGoogleTest(&argc, argv);
  const int status = RUN_ALL_TESTS();
  if (own) {
    if (status == 0)
      fs::remove_all(dir, ec);
    else
      std::cerr << "test files kept in " << dir.string() << "\n";
  }
  return status;
}
