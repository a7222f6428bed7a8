// Inputs found by the libFuzzer targets in fuzz/ (scripts/fuzz.sh). Each must be rejected
// with a clean exception naming the file (or be read successfully), never crash.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
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
    try {
      if (ext == ".kstate") {
        read_state_file(path);
      } else {
        ImportOptions opt;
        opt.max_segments = 20000;
        import_yarns(path, opt);
      }
    } catch (const std::exception& ex) {
      EXPECT_NE(std::string(ex.what()).find(e.path().filename().string()), std::string::npos)
          << path << ": " << ex.what();
    }
  }
  RecordProperty("inputs", count);
}

}  // namespace
}  // namespace knit
