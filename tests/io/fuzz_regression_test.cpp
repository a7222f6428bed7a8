// Inputs found by the libFuzzer targets in fuzz/ (scripts/fuzz.sh) and hand-made hostile
// inputs, in tests/data/io/fuzz/. Each must be rejected with a clean exception naming the
// file, never crash. Every reader has at least one.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "knit/io/import.hpp"
#include "knit/io/state_file.hpp"
#include "knit/pattern/pattern.hpp"
#include "knit/scene/scene.hpp"

namespace knit {
namespace {

namespace fs = std::filesystem;

TEST(IoFuzzRegression, EveryKeptInputFailsCleanly) {
  const fs::path dir = fs::path(KNIT_TEST_DATA) / "io" / "fuzz";
  // extension → reader
  std::map<std::string, int> count = {{".yarns", 0},  {".bcc", 0},  {".obj", 0},
                                      {".kstate", 0}, {".json", 0}, {".chart", 0}};
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string path = e.path().string();
    const std::string ext = e.path().extension().string();
    if (!count.count(ext)) continue;
    ++count[ext];
    std::string message;
    try {
      if (ext == ".kstate") {
        read_state_file(path);
      } else if (ext == ".json") {
        load_scene(path);
      } else if (ext == ".chart") {
        load_pattern(path);
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
  int total = 0;
  for (const auto& [ext, n] : count) {
    EXPECT_GT(n, 0) << "no " << ext << " input in " << dir;
    total += n;
  }
  RecordProperty("inputs", total);
}

}  // namespace
}  // namespace knit
