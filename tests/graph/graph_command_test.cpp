// knitsim graph: a knitout program's knit graph as JSON, and a refused program's message.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>
#include <string>

#include "app/run_knitsim.hpp"

namespace knit {
namespace {

using cli_test::run;

const std::string KNITOUT = std::string(KNIT_TEST_DATA) + "/knitout/";

TEST(GraphCommand, PrintsTheGraphOfAProgramAsJson) {
  // the decrease sheet: one carrier, stacked decreases, the top course dropped at the end
  const cli_test::Result r = run("graph " + KNITOUT + "decrease.knitout --loops");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  const auto& loops = j["loop_list"];
  EXPECT_EQ(j["loops"]["total"].get<std::size_t>(), loops.size());
  ASSERT_EQ(j["yarns"].size(), 1u);
  EXPECT_EQ(j["yarns"][0]["carrier"], "3");
  EXPECT_EQ(j["yarns"][0]["loops"].get<std::size_t>(), loops.size());
  // every parent is listed before its child, and some loop has two (a decrease)
  std::size_t stacked = 0;
  for (const auto& l : loops) {
    for (const auto& p : l["parents"]) EXPECT_LT(p.get<int>(), l["id"].get<int>());
    stacked += l["parents"].size() >= 2;
  }
  EXPECT_GT(stacked, 0u);
  // the dropped top course: each a loop that was made and then dropped by a later line
  ASSERT_FALSE(j["free_loops"]["dropped"].empty());
  for (const auto& f : j["free_loops"]["dropped"])
    EXPECT_GT(f["dropped_line"].get<int>(), f["line"].get<int>());
  EXPECT_TRUE(j["free_loops"]["live"].empty());
  EXPECT_TRUE(j["problems"].empty());
  // what relax lays of it: nothing yet, and why (its first decrease's line)
  EXPECT_FALSE(j["sheet"]["laid"].get<bool>());
  EXPECT_NE(j["sheet"]["why_not"].get<std::string>().find("decrease.knitout:140: 'knit - f9 3': a "
                                                          "decrease"),
            std::string::npos)
      << j["sheet"];
}

TEST(GraphCommand, SaysWhatRelaxLaysOfAProgram) {
  // the letter k in purls on stockinette: 11 rows of 14, its first pass from the right
  const cli_test::Result r = run("graph " + KNITOUT + "k.knitout");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json s = nlohmann::json::parse(r.output)["sheet"];
  EXPECT_TRUE(s["laid"].get<bool>());
  EXPECT_EQ(s["rows"], 11);
  EXPECT_EQ(s["cols"], 14);
  EXPECT_EQ(s["in_the_round"], false);
  EXPECT_EQ(s["first_row_leftward"], true);
}

TEST(GraphCommand, ARefusedProgramNamesItsLineAndExitsOne) {
  const std::string dir = cli_test::temp_dir("graph_refused");
  std::filesystem::create_directories(dir);
  const std::string prog = dir + "/bad.k";
  {
    std::ofstream out(prog);
    out << ";!knitout-2\nin 1\nknit + f1 1\nrack 1\nxfer f1 b1\n";
  }
  const std::string json = dir + "/out.json";
  const cli_test::Result r = run("graph " + prog + " --out " + json);
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("bad.k:5: 'xfer f1 b1'"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(json));  // nothing written
}

// a chart goes through the same command: a 4-stitch stockinette with one c4f row
TEST(GraphCommand, PrintsTheGraphOfAChart) {
  const std::string path = cli_test::temp_dir("graph_chart") + ".chart";
  std::ofstream(path) << "k k k k\nc4f\nk k k k\n";
  const cli_test::Result r = run("graph " + path + " --loops");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["rows"], 3);
  // 4 cast on and 4 a row, three rows; the last row's 4 stay live
  EXPECT_EQ(j["loops"]["total"], 16);
  EXPECT_EQ(j["loop_list"].size(), 16u);
  EXPECT_EQ(j["free_loops"]["live"].size(), 4u);
  EXPECT_TRUE(j["free_loops"]["dropped"].empty());
  // the cable: each of its two front loops crosses each of its two back loops
  EXPECT_EQ(j["crossings"].size(), 4u);
  EXPECT_TRUE(j["problems"].empty());
}

}  // namespace
}  // namespace knit
