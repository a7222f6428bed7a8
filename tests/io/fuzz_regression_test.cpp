// Inputs found by the libFuzzer targets in fuzz/ (scripts/fuzz.sh). Each must be rejected
// with a clean exception naming the file, never crash.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "knit/io/import.hpp"
#include "knit/io/state_file.hpp"

namespace knit {
namespace {

namespace fs = std::filesystem;

TEST(IoFuzzRegression, EveryKeptInputFailsCleanly) {
  const fs::path dir = fs::path(KNIT_TEST_DATA) / "io" / "fuzz";
  int count = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string path = e.path().string();
    const std::string ext = e.path().extension().string();
    if (ext != ".yarns" && ext != ".bcc" && ext != ".obj" && ext != ".kstate") continue;
    ++count;
    std::string message;
    try {
      if (ext == ".kstate") {
        read_state_file(path);
      } else {
        import_yarns(path);
      }
    } catch (const std::exception& ex) {
      message = ex.what();
    }
    std::cout << e.path().filename().string() << ": " << message << "\n";
    EXPECT_FALSE(message.empty()) << path << " was accepted";
    EXPECT_NE(message.find(e.path().filename().string()), std::string::npos) << message;
  }
  RecordProperty("inputs", count);
}

}  // namespace
}  // namespace knit
