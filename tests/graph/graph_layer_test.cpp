// The knit graph is the bottom layer of the library: its sources include the standard
// library, each other, and the input-file limits alone (docs/knit-graph.md).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

namespace knit {
namespace {

TEST(GraphLayer, IncludesNothingAboveIt) {
  const std::filesystem::path dir = std::filesystem::path(KNIT_SOURCE_DIR) / "src/knit/graph";
  const std::regex include(R"(^\s*#\s*include\s*([<"])([^>"]+)[>"])");
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    ++files;
    std::ifstream in(e.path());
    for (std::string line; std::getline(in, line);) {
      std::smatch m;
      if (!std::regex_search(line, m, include)) continue;
      const std::string header = m[2];
      if (m[1] == "<") {
        // the standard library: no directory, no extension
        EXPECT_EQ(header.find_first_of("./"), std::string::npos)
            << e.path().filename() << " includes <" << header << ">";
        continue;
      }
      const bool own = header.rfind("knit/graph/", 0) == 0;
      const bool input_file =
          header == "knit/io/input_file.hpp" || header == "knit/util/input_file.hpp";
      EXPECT_TRUE(own || input_file) << e.path().filename() << " includes \"" << header << "\"";
    }
  }
  EXPECT_GE(files, 4);
}

}  // namespace
}  // namespace knit
