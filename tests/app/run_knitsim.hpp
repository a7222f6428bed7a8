#pragma once
// Running the knitsim program from a test: its exit code and everything it printed.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

namespace knit::cli_test {

struct Result {
  int code;
  std::string output;  ///< stdout and stderr together
};

/// Runs `knitsim ARGS` (the build's program) through the shell.
inline Result run(const std::string& args) {
  const std::string cmd = std::string(KNIT_APP) + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  while (size_t n = fread(buf.data(), 1, buf.size(), pipe)) out.append(buf.data(), n);
  const int status = pclose(pipe);
  return {WEXITSTATUS(status), out};
}

/// A path in the test's temporary folder, removed first if it exists.
inline std::string temp_dir(const std::string& name) {
  const std::filesystem::path p = std::filesystem::path(::testing::TempDir()) / name;
  std::filesystem::remove_all(p);
  return p.string();
}

}  // namespace knit::cli_test
