// What knitsim says when things go right (issue 51): success lines in numbers a user
// reads (a few digits and a unit, "not measured" for what a run did not measure, never
// JSON's null), inputs known by their contents, a short pull that works, and notes where
// knitsim does other than asked. The refusals are in hostile_input_test.cpp.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <thread>

#include "knit/io/state_file.hpp"
#include "knit/model/params.hpp"
#include "knit/recipes/stretch.hpp"
#include "run_knitsim.hpp"

namespace {

namespace fs = std::filesystem;

using knit::cli_test::Result;
using knit::cli_test::run;
using knit::cli_test::temp_dir;

const std::string KNIT = std::string(KNIT_EXAMPLES) + "/knits/stockinette_12x12.kstate";

// the numbers a line prints (up to the path it ends with): none has more than `digits`
// significant digits
void expect_short_numbers(const std::string& whole, int digits) {
  const std::string line = whole.substr(0, whole.find('/'));
  static const std::regex number(R"((\d+)\.?(\d*))");
  for (auto it = std::sregex_iterator(line.begin(), line.end(), number);
       it != std::sregex_iterator(); ++it) {
    std::string all = (*it)[1].str() + (*it)[2].str();
    all.erase(0, std::min(all.find_first_not_of('0'), all.size()));
    EXPECT_LE(static_cast<int>(all.size()), digits) << it->str() << " in: " << line;
  }
}

// a knitout program named .txt is relaxed as the program (its own size), and the line
// that says how it went prints its measures with their units
TEST(Messages, AKnitoutProgramOfAnyNameRelaxesAtItsSize) {
  std::ifstream in(std::string(KNIT_TEST_DATA) + "/yarns/swatch4x4garter.k");
  const std::string program = ::testing::TempDir() + "/msg_garter.txt";
  std::ofstream(program) << in.rdbuf();
  const std::string out = temp_dir("msg_knitout_txt");
  const Result r = run("relax " + program + " --max-time 0.001 --quiet --no-frames --out " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  const knit::StateFile f = knit::read_state_file(out + "/relaxed.kstate");
  ASSERT_TRUE(f.knit.has_value());
  EXPECT_EQ(f.knit->rows, 4);
  EXPECT_EQ(f.knit->cols, 4);
  const size_t at = r.output.find("relaxed " + program);
  ASSERT_NE(at, std::string::npos) << r.output;
  const std::string line = r.output.substr(at + 8 + program.size());
  EXPECT_NE(line.find(" cm, wale "), std::string::npos) << line;
  EXPECT_EQ(line.find("null"), std::string::npos) << line;
  expect_short_numbers(line.substr(0, line.find('\n')), 4);
}

// a pull inside --to's range but shorter than the spacing of the samples runs, sampled
// at its ends; its line prints the force shortly and says the stiffness was not measured
TEST(Messages, AShortPullRunsAndSaysWhatItDidNotMeasure) {
  const std::string out = temp_dir("msg_short_pull");
  const Result r =
      run("stretch --from " + KNIT + " --to 0.005 --no-render --no-frames -q --out " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream csv(out + "/stretch.csv");
  std::string header, row, last;
  std::getline(csv, header);
  int rows = 0;
  for (; std::getline(csv, row); ++rows) last = row;
  EXPECT_GE(rows, 2);
  const double strain = std::stod(last.substr(last.find(',') + 1));
  EXPECT_NEAR(strain, 0.005, 1e-6) << last;
  const size_t at = r.output.find("stretched course to strain 0.005");
  ASSERT_NE(at, std::string::npos) << r.output;
  const std::string line = r.output.substr(at, r.output.find('\n', at) - at);
  EXPECT_NE(line.find("stiffness not measured"), std::string::npos) << line;
  EXPECT_NE(line.find(" dyn, "), std::string::npos) << line;
  EXPECT_EQ(line.find("null"), std::string::npos) << line;
  expect_short_numbers(line, 4);
  // the summary keeps the nulls and the spacing asked, for tools that read it
  std::ifstream in(out + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_TRUE(s["stretch"]["stiffness_small_strain"].is_null());
  EXPECT_EQ(s["output_strain"], 0.01);
}

// more threads than the machine runs: a one-line note, and the run goes on
TEST(Messages, MoreThreadsThanCoresAreNoted) {
  const unsigned cores = std::thread::hardware_concurrency();
  if (cores >= 4096) GTEST_SKIP() << cores << " cores";
  const std::string out = temp_dir("msg_threads");
  const Result r =
      run("relax stockinette --rows 2 --cols 2 --max-time 0.0005 --quiet --no-frames "
          "-j 4096 --out " +
          out);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("knitsim: note: --threads 4096: this machine runs"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("; using "), std::string::npos) << r.output;
}

// the time left in a resume command: short where the run goes on with the same whole
// steps, else exactly what ends the run where it was to end
TEST(Messages, TheTimeLeftOfAResumeIsShortAndEndsTheRunWhereItWasToEnd) {
  const double h = 1e-4;
  double t = 0;
  for (int k = 0; k < 350; ++k) t += h;  // a time summed step by step: 0.034999999999999976
  EXPECT_EQ(knit::time_left_text(t, 0.04, h), "0.005");
  // a time left that is not whole steps: the shortest decimal that ends at the end exactly
  const double from = 0.0123, to = 0.04;
  const std::string left = knit::time_left_text(from, to, 3e-4);
  EXPECT_EQ(from + std::stod(left), to) << left;
  EXPECT_EQ(left, "0.0277");
  double sum = 0;
  for (int k = 0; k < 50; ++k) sum += 1.0 / 11800;
  const std::string odd = knit::time_left_text(sum, 0.01, 3e-4);
  EXPECT_EQ(sum + std::stod(odd), 0.01) << odd;
}

}  // namespace
