#include "knit/analysis/rest_reference.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace knit {
namespace {

namespace fs = std::filesystem;

// the part of a `knitsim relax` summary that a reference is read by
nlohmann::json summary(const std::string& pattern, int rows, int cols, bool relaxed) {
  return {{"pattern", pattern},
          {"rows", rows},
          {"cols", cols},
          {"relaxed", relaxed},
          {"course_length_cm", 20.0},
          {"wale_length_cm", 25.0},
          {"stitch_width_cm", 0.8},
          {"row_height_cm", 0.7},
          {"course_extent_cm", 10.0},
          {"wale_extent_cm", 28.0},
          {"edge_curl", 0.5},
          {"potential_energy", 7900.0}};
}

class RestReferenceFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() /
          ("knit_rest_reference_" +
           std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir / "rib2x2");
  }
  void TearDown() override { fs::remove_all(dir); }
  void write(const std::string& text) { std::ofstream(dir / "rib2x2" / "summary.json") << text; }
  // the message read_rest_reference throws with, "" if it reads the file
  std::string refusal(const std::string& pattern = "rib2x2", int rows = 42, int cols = 32) {
    try {
      read_rest_reference(dir.string(), pattern, rows, cols);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir;
};

TEST_F(RestReferenceFile, ReadsARelaxationAtRestOfTheSameKnit) {
  write(summary("rib2x2", 42, 32, true).dump());
  EXPECT_EQ(refusal(), "");
  EXPECT_EQ(read_rest_reference(dir.string(), "rib2x2", 42, 32)["edge_curl"], 0.5);
}

TEST_F(RestReferenceFile, RefusesWhatIsNotOneNamingTheFileAndWhy) {
  const std::string file = (dir / "rib2x2" / "summary.json").string();
  // no file at all (another pattern's directory is missing)
  EXPECT_NE(refusal("garter").find((dir / "garter" / "summary.json").string() + ": cannot be read"),
            std::string::npos);
  const struct {
    std::string text, pattern;
    int rows, cols;
    std::string says;
  } cases[] = {
      {"{\"pattern\":", "rib2x2", 42, 32, "not JSON"},
      {"[1, 2]", "rib2x2", 42, 32, "not the summary of a `knitsim relax` run"},
      {summary("garter", 42, 32, true).dump(), "rib2x2", 42, 32,
       "a relaxation of \"garter\", not of rib2x2"},
      {summary("rib2x2", 12, 12, true).dump(), "rib2x2", 42, 32, "a 12×12 sample, not 42×32"},
      {summary("rib2x2", 42, 32, false).dump(), "rib2x2", 42, 32,
       "not at rest (\"relaxed\": false)"},
  };
  for (const auto& c : cases) {
    write(c.text);
    const std::string why = refusal(c.pattern, c.rows, c.cols);
    EXPECT_EQ(why.rfind(file + ": ", 0), 0u) << why;
    EXPECT_NE(why.find(c.says), std::string::npos) << why;
  }
  for (const char* key : REST_SHAPE_KEYS) {
    nlohmann::json s = summary("rib2x2", 42, 32, true);
    s.erase(key);
    write(s.dump());
    EXPECT_NE(refusal().find(std::string("no finite \"") + key + "\""), std::string::npos) << key;
    s[key] = "wide";
    write(s.dump());
    EXPECT_NE(refusal().find(std::string("no finite \"") + key + "\""), std::string::npos) << key;
  }
}

TEST(RestReference, ComparesEachMeasureAndTheLargestOfWidthHeightGauge) {
  const nlohmann::json ref = summary("stockinette", 42, 32, true);
  nlohmann::json run = ref;
  EXPECT_EQ(compare_rest_shape(run, ref)["max_abs_width_height_gauge"], 0.0);

  run["course_length_cm"] = 21.0;  // 5 % wider
  run["row_height_cm"] = 0.63;     // 10 % shorter rows: the largest
  run["course_extent_cm"] = 15.0;  // 50 %: an extent, not in the largest
  run["edge_curl"] = 0.2;          // curl by its difference in stitch widths
  const nlohmann::json d = compare_rest_shape(run, ref);
  EXPECT_NEAR(d["course_length_cm"].get<double>(), 0.05, 1e-12);
  EXPECT_NEAR(d["row_height_cm"].get<double>(), -0.1, 1e-12);
  EXPECT_NEAR(d["course_extent_cm"].get<double>(), 0.5, 1e-12);
  EXPECT_NEAR(d["edge_curl_difference"].get<double>(), -0.3, 1e-12);
  EXPECT_FALSE(d.contains("edge_curl"));
  EXPECT_NEAR(d["max_abs_width_height_gauge"].get<double>(), 0.1, 1e-12);

  // a measure missing on one side, or 0 in the reference, is left out
  run.erase("row_height_cm");
  nlohmann::json ref0 = ref;
  ref0["course_length_cm"] = 0.0;
  const nlohmann::json d2 = compare_rest_shape(run, ref0);
  EXPECT_FALSE(d2.contains("row_height_cm"));
  EXPECT_FALSE(d2.contains("course_length_cm"));
  EXPECT_NEAR(d2["max_abs_width_height_gauge"].get<double>(), 0.0, 1e-12);
}

}  // namespace
}  // namespace knit
