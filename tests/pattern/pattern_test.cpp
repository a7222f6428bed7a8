#include "knit/pattern/pattern.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace knit {
namespace {

std::string error_of(const std::string& text) {
  try {
    parse_chart(text, "swatch.chart");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Pattern, ChartRowsReadBottomUpLikeAKnittingChart) {
  const Pattern p = parse_chart("# comment only\n\nKP  # top row\n\n  p k\t\n", "test");
  ASSERT_EQ(p.num_rows(), 2);
  ASSERT_EQ(p.num_cols(), 2);
  EXPECT_EQ(p.rows[0], "pk");  // the last line is row 0
  EXPECT_EQ(p.rows[1], "kp");
  EXPECT_FALSE(p.is_knit(0, 0));
  EXPECT_TRUE(p.is_knit(1, 0));
}

TEST(Pattern, ChartErrorsNameSourceLineAndColumn) {
  EXPECT_NE(error_of("kk\nkx\n").find("swatch.chart:2:2"), std::string::npos)
      << error_of("kk\nkx\n");
  EXPECT_NE(error_of("kk\nkx\n").find("'x'"), std::string::npos);
  const std::string lengths = error_of("kkp\n\nkp\n");
  EXPECT_NE(lengths.find("swatch.chart:3:"), std::string::npos) << lengths;
  EXPECT_NE(lengths.find("same length"), std::string::npos) << lengths;
  const std::string empty = error_of("# nothing\n\n");
  EXPECT_NE(empty.find("swatch.chart"), std::string::npos) << empty;
  EXPECT_NE(empty.find("empty chart"), std::string::npos) << empty;
  EXPECT_NE(error_of("").find("empty chart"), std::string::npos);
}

TEST(Pattern, UnprintableCharactersAreEscapedInErrors) {
  // a NUL, a control character or a UTF-8 byte is shown by its value, never raw
  const std::string nul = error_of(std::string("kp\nk\0p\n", 7));
  EXPECT_NE(nul.find("swatch.chart:2:2: unknown stitch byte 0x00"), std::string::npos) << nul;
  EXPECT_EQ(nul.find('\0'), std::string::npos);
  const std::string utf8 = error_of("k\xc3\xa9p\n");
  EXPECT_NE(utf8.find("swatch.chart:1:2: unknown stitch byte 0xC3 (not ASCII"), std::string::npos)
      << utf8;
  EXPECT_NE(error_of("k\x7f\n").find("byte 0x7F"), std::string::npos);
  // a UTF-8 byte-order mark at the start is not part of the chart
  EXPECT_EQ(parse_chart("\xef\xbb\xbfkp\n", "bom.chart").num_cols(), 2);
}

TEST(Pattern, TileRepeatsTheChart) {
  const Pattern t = tile(parse_chart("kp\npk\nkk\n", "t"), 5, 5);
  ASSERT_EQ(t.num_rows(), 5);
  ASSERT_EQ(t.num_cols(), 5);
  EXPECT_EQ(t.rows[0], "kkkkk");
  EXPECT_EQ(t.rows[1], "pkpkp");
  EXPECT_EQ(t.rows[2], "kpkpk");
  EXPECT_EQ(t.rows[3], "kkkkk");
  EXPECT_EQ(t.rows[4], "pkpkp");
  EXPECT_THROW(tile(t, 0, 3), std::invalid_argument);
  EXPECT_THROW(tile(Pattern{}, 2, 2), std::invalid_argument);
}

TEST(Pattern, BuiltinsHaveTheirStitchLayouts) {
  const Pattern st = tile(builtin_pattern("stockinette"), 4, 6);
  const Pattern garter = tile(builtin_pattern("garter"), 4, 6);
  const Pattern rib2 = tile(builtin_pattern("rib2x2"), 4, 8);
  const Pattern rib1 = tile(builtin_pattern("rib1x1"), 4, 6);
  const Pattern seed = tile(builtin_pattern("seed"), 4, 6);
  for (int r = 0; r < 4; ++r) {
    EXPECT_EQ(st.rows[r], "kkkkkk");                              // every loop to the front
    EXPECT_EQ(garter.rows[r], r % 2 == 0 ? "kkkkkk" : "pppppp");  // rows alternate
    EXPECT_EQ(rib2.rows[r], "kkppkkpp");
    EXPECT_EQ(rib1.rows[r], "kpkpkp");
    EXPECT_EQ(seed.rows[r], r % 2 == 0 ? "kpkpkp" : "pkpkpk");
  }
  EXPECT_EQ(builtin_pattern("Reverse_Stockinette").rows[0], "p");
  for (const auto& name : builtin_pattern_names()) EXPECT_NO_THROW(builtin_pattern(name)) << name;
  try {
    builtin_pattern("moss");
    FAIL() << "no error for an unknown pattern";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("moss"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("stockinette"), std::string::npos);
  }
}

TEST(Pattern, LoadsBuiltinsByNameAndChartsByPath) {
  EXPECT_EQ(load_pattern("garter").rows, builtin_pattern("garter").rows);
  const Pattern p = load_pattern(std::string(KNIT_TEST_DATA) + "/patterns/rib_and_seed.chart");
  ASSERT_EQ(p.num_rows(), 3);
  EXPECT_EQ(p.rows[0], "kkpp");
  EXPECT_EQ(p.rows[1], "kpkp");
  EXPECT_EQ(p.rows[2], "kkpp");
  try {
    load_pattern("no/such/file.chart");
    FAIL() << "no error for a missing chart";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no/such/file.chart"), std::string::npos);
  }
}

}  // namespace
}  // namespace knit
