// The help texts and exit codes of the knitsim program, read from outside: every command's
// --help is parsed as a user reads it (docs/cli.md, "Reading --help"), whatever declares
// the options, and the exit codes are those docs/cli.md's table gives.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "app/run_knitsim.hpp"

namespace {

using knit::cli_test::Result;
using knit::cli_test::run;
using knit::cli_test::temp_dir;

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(' ');
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(' ') - a + 1);
}

// One entry of a --help listing: "  NAMES [TYPE …]   description…" and its continuation
// lines, under a heading such as "Options:".
struct Entry {
  std::string heading, names, type, text;
};

std::vector<Entry> entries_of(const std::string& help) {
  std::vector<Entry> out;
  std::string heading;
  bool in_entry = false;
  for (const std::string& line : lines_of(help)) {
    if (line.empty() || line[0] != ' ') {  // a heading, the usage line, the footer
      heading = line;
      in_entry = false;
      continue;
    }
    if (line.size() > 2 && line[2] != ' ') {  // a new entry
      const std::string body = line.substr(2);
      const size_t gap = body.find("  ");
      const std::string head = body.substr(0, gap);
      Entry e;
      e.heading = heading;
      std::istringstream words(head);
      words >> e.names;
      std::string second;
      if (words >> second &&
          second.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZ:_") == std::string::npos &&
          second != "REQUIRED")
        e.type = second;
      e.text = gap == std::string::npos ? "" : trim(body.substr(gap));
      out.push_back(e);
      in_entry = true;
    } else if (in_entry) {
      out.back().text += (out.back().text.empty() ? "" : " ") + trim(line);
    }
  }
  return out;
}

std::vector<std::string> commands() {
  const Result top = run("--help");
  EXPECT_EQ(top.code, 0) << top.output;
  std::vector<std::string> names;
  for (const Entry& e : entries_of(top.output))
    if (e.heading.rfind("Subcommands", 0) == 0) names.push_back(e.names);
  return names;
}

// a leading number of `text` ("0.3", "8.47e-05 (1/11800)", "0 (all cores)"), if any
bool leading_number(const std::string& text, double& x) {
  char* end = nullptr;
  x = std::strtod(text.c_str(), &end);
  return end != text.c_str() && (*end == '\0' || *end == ' ' || *end == ',');
}

struct ValueLine {
  std::string unit, default_text, range;
};

bool value_line(const std::string& text, ValueLine& v) {
  const size_t at = text.rfind("unit: ");
  if (at == std::string::npos) return false;
  static const std::regex form("unit: (.+?); default: (.+?)(?:; range: (.+))?");
  std::smatch m;
  const std::string tail = text.substr(at);
  if (!std::regex_match(tail, m, form)) return false;
  v = {m[1], m[2], m[3]};
  return true;
}

TEST(Help, EveryOptionSaysItsUnitDefaultAndRange) {
  const std::vector<std::string> names = commands();
  for (const char* expected :
       {"simulate", "relax", "stretch", "export", "render", "plot", "mesh", "view", "version"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  const std::set<std::string> types = {"INT", "FLOAT", "PATH", "NAME", "TEXT"};
  const std::regex range_form(R"([\[(]([-+0-9.e]+), ([-+0-9.e]+)\].*)");
  // option → unit in each command that takes it: the same option says the same thing
  std::map<std::string, std::map<std::string, std::string>> units;
  int checked = 0;
  for (const std::string& cmd : names) {
    const Result r = run(cmd + " --help");
    ASSERT_EQ(r.code, 0) << cmd << ":\n" << r.output;
    EXPECT_NE(r.output.find("Exit codes"), std::string::npos) << cmd << ": no exit codes";
    EXPECT_NE(r.output.find("docs/cli.md"), std::string::npos) << cmd << ": no pointer to docs";
    for (const Entry& e : entries_of(r.output)) {
      if (e.heading.rfind("Usage", 0) == 0 || e.type.empty()) continue;  // a flag
      const std::string where = cmd + " " + e.names;
      ++checked;
      EXPECT_TRUE(types.count(e.type)) << where << ": value type " << e.type;
      ValueLine v;
      if (!value_line(e.text, v)) {
        ADD_FAILURE() << where << ": no \"unit: …; default: …\" in\n" << e.text;
        continue;
      }
      EXPECT_FALSE(trim(v.unit).empty()) << where;
      EXPECT_FALSE(trim(v.default_text).empty()) << where;
      units[e.names][cmd] = v.unit;
      if (e.type != "INT" && e.type != "FLOAT") continue;
      std::smatch m;
      if (!std::regex_match(v.range, m, range_form)) {
        ADD_FAILURE() << where << ": a number without a range [lo, hi] (\"" << v.range << "\")";
        continue;
      }
      const double lo = std::stod(m[1]), hi = std::stod(m[2]);
      EXPECT_LE(lo, hi) << where;
      double d = 0;
      if (leading_number(v.default_text, d)) {
        const bool open = v.range[0] == '(';
        EXPECT_TRUE((open ? d > lo : d >= lo) && d <= hi)
            << where << ": default " << v.default_text << " outside its range " << v.range;
      }
    }
  }
  EXPECT_GT(checked, 80);  // every command's options, not a few
  for (const auto& [option, by_command] : units) {
    const std::string& first = by_command.begin()->second;
    for (const auto& [cmd, unit] : by_command)
      EXPECT_EQ(unit, first) << option << " is in " << unit << " in " << cmd << " but in " << first
                             << " in " << by_command.begin()->first;
  }
}

TEST(Help, TheSolverOptionsAreOneGroupSaidOnce) {
  // simulate, relax and stretch list the shared solver options in one group, each option
  // with the same text in every command (its default aside)
  std::map<std::string, std::string> text;
  for (const char* cmd : {"simulate", "relax", "stretch"}) {
    const Result r = run(std::string(cmd) + " --help");
    int in_group = 0;
    for (const Entry& e : entries_of(r.output)) {
      if (e.heading.rfind("Solver options", 0) != 0) continue;
      ++in_group;
      const std::string doc = e.text.substr(0, e.text.rfind("unit: "));
      if (!text.count(e.names)) text[e.names] = doc;
      EXPECT_EQ(doc, text[e.names]) << cmd << " " << e.names;
    }
    EXPECT_GE(in_group, 6) << cmd << ":\n" << r.output;
    // the integrators are explained once, in docs/cli.md, not in a paragraph per command
    EXPECT_EQ(r.output.find("42×32 knit hanging"), std::string::npos) << cmd;
  }
  for (const char* option : {"--time-step", "--integrator", "--implicit-bending",
                             "--contact-solve-tolerance", "--contact-reuse", "--max-step-halvings"})
    EXPECT_TRUE(text.count(option)) << option;
}

TEST(Help, TheDampingRatesReadTheSameInRelaxAndStretch) {
  // one filter, one unit: relax and stretch differ only in their defaults (the relaxation
  // and simulation columns of MODEL.md §8)
  std::map<std::string, std::string> doc;
  for (const char* cmd : {"relax", "stretch"})
    for (const Entry& e : entries_of(run(std::string(cmd) + " --help").output))
      if (e.names == "--alpha-small" || e.names == "--alpha-large") {
        ValueLine v;
        ASSERT_TRUE(value_line(e.text, v)) << cmd << " " << e.names;
        EXPECT_NE(v.unit.find("per 1/11800 s"), std::string::npos) << cmd << " " << v.unit;
        const std::string key = e.names;
        const std::string d = e.text.substr(0, e.text.rfind("unit: ")) + v.unit + v.range;
        if (doc.count(key))
          EXPECT_EQ(doc[key], d) << key;
        else
          doc[key] = d;
      }
  EXPECT_EQ(doc.size(), 2u);
}

// The code docs/cli.md's exit-code table gives the row that mentions `what`.
int documented_code(const std::string& what) {
  std::ifstream in(std::string(KNIT_SOURCE_DIR) + "/docs/cli.md");
  EXPECT_TRUE(in) << "docs/cli.md";
  bool in_table = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("## ", 0) == 0) in_table = line == "## Exit codes";
    if (!in_table || line.rfind("| ", 0) != 0) continue;
    if (line.find(what) == std::string::npos) continue;
    return std::atoi(line.c_str() + 2);
  }
  ADD_FAILURE() << "docs/cli.md's exit codes say nothing of " << what;
  return -1;
}

TEST(Help, ExitCodesAreTheDocumentedOnes) {
  const std::string out = temp_dir("help_exit_codes");
  EXPECT_EQ(run("--help").code, documented_code("--help"));
  EXPECT_EQ(run("version").code, documented_code("done"));
  // a bad option: unknown, or a value outside its range
  const Result unknown = run("relax stockinette --bogus --out " + out);
  EXPECT_EQ(unknown.code, documented_code("unknown option")) << unknown.output;
  const Result range = run("relax stockinette --rows 1 --out " + out);
  EXPECT_EQ(range.code, documented_code("outside its range")) << range.output;
  EXPECT_NE(range.output.find("--rows"), std::string::npos) << range.output;
  // a missing file, found by the option's check or by the reader
  const Result missing = run("simulate " + out + "_nowhere.json --out " + out);
  EXPECT_EQ(missing.code, documented_code("missing file")) << missing.output;
  EXPECT_NE(missing.output.find("_nowhere.json"), std::string::npos) << missing.output;
  const Result missing_resume = run("relax --resume " + out + "_nowhere.kstate --out " + out);
  EXPECT_EQ(missing_resume.code, documented_code("missing file")) << missing_resume.output;
  // bad input: a malformed scene
  const std::string scene = out + "_bad.json";
  std::ofstream(scene) << R"({"yarns": [})";
  const Result bad = run("simulate " + scene + " --out " + out);
  EXPECT_EQ(bad.code, documented_code("malformed scene")) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(out));  // nothing ran
  // a run that fails partway
  const std::string unstable = out + "_unstable.json";
  std::ofstream(unstable)
      << R"({"yarns": [{"line": {"from": [0,0,0], "to": [5,0,0], "segments": 10}}],
             "params": {"k_bend": 1e6}, "time_step": 0.01, "duration": 1})";
  const Result failed = run("simulate " + unstable + " --out " + out + " --quiet");
  EXPECT_EQ(failed.code, documented_code("the run failed")) << failed.output;
}

}  // namespace
