// The hostile-input suite: the built knitsim program run on a table of bad inputs (bad
// JSON, missing files, numbers out of range, unknown keys, bad chart stitches, bad
// knitout, bad .kstate bytes, bad CSVs, bad options). For every case: a non-zero exit
// (1 for bad input; a usage error of the options its own code below 128: no signal, no
// crash), a short message naming the file, field, option or line, none of a library's own
// words (json.exception, filesystem error, std::), no raw bytes of the input, and nothing
// left behind (no output, no half-written temporary). cli_test.cpp and reliability_test.cpp
// hold the cases that need more than a message (resumes, signals, what a run writes).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "run_knitsim.hpp"

namespace {

namespace fs = std::filesystem;

using knit::cli_test::Result;
using knit::cli_test::run;

// where the inputs lie and the outputs would go
fs::path dir() {
  static const fs::path d = [] {
    const fs::path p = fs::path(::testing::TempDir()) / "hostile";
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
  }();
  return d;
}

std::string file(const std::string& name, const std::string& bytes) {
  const fs::path p = dir() / name;
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << bytes;
  return p.string();
}

const std::string EXAMPLES = KNIT_EXAMPLES;
const std::string KNIT = EXAMPLES + "/knits/stockinette_12x12.kstate";
const std::string PENDULUM = EXAMPLES + "/pendulum.json";

// a scene of one straight yarn with `fields` added at the top level
std::string scene(const std::string& fields) {
  return R"({"yarns": [{"line": {"from": [0,0,0], "to": [4,0,0], "segments": 8}}])" +
         (fields.empty() ? std::string() : ", " + fields) + "}";
}

// a flat 4 × 4 knitout program (the shipped swatch4x4.k's lines), one line replaced
std::string swatch(int replace_line = 0, const std::string& with = "") {
  std::ifstream in(std::string(KNIT_TEST_DATA) + "/yarns/swatch4x4.k");
  std::string out, line;
  for (int n = 1; std::getline(in, line); ++n) out += (n == replace_line ? with : line) + "\n";
  return out;
}

// a stretch run's summary, as the --fit cases need it
std::string stretch_summary(const std::string& direction, const std::string& stiffness) {
  return R"({"direction": ")" + direction +
         R"(", "model": "yarn", "protocol": "continuous", "to_strain": 0.05,
             "output_strain": 0.01, "clamp_stitches": 2,
             "stretch": {"stiffness_small_strain": )" +
         stiffness + "}}";
}

struct Case {
  std::string args;                        ///< after `knitsim`; {OUT} is this case's output path
  std::vector<std::string> names;          ///< what the message must name
  bool usage = false;                      ///< a usage error (any code below 128), else exit 1
  std::vector<std::string> not_said = {};  ///< what it must not say
};

std::vector<Case> cases() {
  const std::string big_point =
      file("big_point.json", R"({"yarns": [{"points": [[0,0,0],[1e300,0,0],[2,0,0],[3,0,0]]}]})");
  const std::string coincide = file(
      "coincide.json", R"({"yarns": [{"points": [[1,1,1],[1,1,1],[1,1,1],[1,1,1],[2,0,0]]}]})");
  const std::string runs = (dir() / "fit").string();
  file("fit/course/summary.json", stretch_summary("course", "null"));
  file("fit/wale/summary.json", stretch_summary("wale", "null"));
  file("fit/bias/summary.json", stretch_summary("bias", "null"));
  file("fit/typed/summary.json", R"({"direction": "course", "model": 3, "stretch": {}})");
  file("curves/run/stretch.csv", "strain,force_moving_dyn\n0,0\n0.01,5\n");
  const std::string binary = std::string("\xff\xfe\x01\x02\x1b[31m\x80\x00", 10) + "abc";

  return {
      // ---- issue 51: the messages a user met ----
      // a knitout program under another name is read as knitout (not as a chart)
      {"relax " + file("prog_txt.txt", swatch(15, "rack 0.5")) + " --out {OUT}",
       {"prog_txt.txt:16: 'knit + f50 1'", "a new column"},
       false,
       {"unknown stitch"}},
      {"relax " + file("prog.knitout", swatch(16, "frobnicate 3")) + " --out {OUT}",
       {"prog.knitout:16: 'frobnicate 3'"}},
      // a mistyped needle is blamed on its own line, with its instruction
      {"relax " + file("typo.k", swatch(13, "knit + f-3 1")) + " --out {OUT}",
       {"typo.k:13: 'knit + f-3 1'", "needle f-3 is not beside f48"}},
      {"relax " + file("typo.txt", swatch(13, "knit + f-3 1")) + " --out {OUT}",
       {"typo.txt:13: 'knit + f-3 1'"}},
      {"relax " + file("short_row.k", swatch(21, "knit + f48 1")) + " --out {OUT}",
       {"short_row.k:21: 'knit + f48 1'", "row 2"}},
      // a yarn point far away: named with its field path and value
      {"simulate " + big_point + " --out {OUT}", {"yarns[0].points[1][0]", "1e+300", "±1e+06 cm"}},
      {"simulate " + file("big_line.json", R"({"yarns": [{"line": {"from": [0,0,0],
                     "to": [-1e7,0,0], "segments": 4}}]})") +
           " --out {OUT}",
       {"yarns[0].line.to[0]", "-1e+07"}},
      {"simulate " + file("big_helix.json", R"({"yarns": [{"helix": {"radius": 1e300,
                     "pitch": 1, "turns": 2, "segments": 8}}]})") +
           " --out {OUT}",
       {"yarns[0].helix.radius", "1e+300"}},
      {"simulate " + coincide + " --out {OUT}", {"yarns[0]", "segment 0 has zero length"}},
      // integers out of range: the real range and the value given
      {"simulate " + file("segments.json", R"({"yarns": [{"line": {"from": [0,0,0], "to": [1,0,0],
                     "segments": 2147483648}}]})") +
           " --out {OUT}",
       {"yarns[0].line.segments", "from 1 to 200000", "got 2147483648"}},
      {"simulate " +
           file("segments_u64.json", R"({"yarns": [{"line": {"from": [0,0,0], "to": [1,0,0],
                     "segments": 18446744073709551615}}]})") +
           " --out {OUT}",
       {"yarns[0].line.segments", "from 1 to 200000", "18446744073709551615"}},
      {"simulate " + file("segments_neg.json", R"({"yarns": [{"circle": {"radius": 1,
                     "segments": -3}}]})") +
           " --out {OUT}",
       {"yarns[0].circle.segments", "got -3"}},
      {"simulate " + file("pin_t.json", scene(R"("pins": [{"yarn": 0, "segment": 1, "t": 1.5}])")) +
           " --out {OUT}",
       {"pins[0].t", "got 1.5"}},
      {"simulate " +
           file("pin_v.json",
                scene(R"("pins": [{"yarn": 0, "at": "end", "velocity": [0,1e300,0]}])")) +
           " --out {OUT}",
       {"pins[0].velocity[1]", "1e+300", "cm/s"}},
      {"simulate " + file("degrees.json", R"({"yarns": [{"circle": {"radius": 1, "degrees": 400,
                     "segments": 8}}]})") +
           " --out {OUT}",
       {"yarns[0].circle.degrees", "got 400"}},
      {"simulate " + file("alpha.json", R"({"knits": [{"state": ")" + KNIT + R"("}],
                     "params": {"alpha_small": 2}})") +
           " --out {OUT}",
       {"params.alpha_small", "alpha_small = 2", "[0, 1]"}},
      {"simulate " + file("knit_far.json", R"({"knits": [{"state": ")" + KNIT + R"(",
                     "translate": [0, 0, 5e6]}]})") +
           " --out {OUT}",
       {"knits[0].translate[2]", "5e+06"}},
      {"simulate " + file("ball.json", scene(R"("objects": [{"sphere": {"radius": 1e9}}])")) +
           " --out {OUT}",
       {"objects[0].sphere.radius", "1e+09"}},
      // a key given twice is refused, named with its place
      {"simulate " +
           file("twice.json",
                "{\"duration\": 0.01,\n \"duration\": 0.02,\n" + scene("").substr(1)) +
           " --out {OUT}",
       {"twice.json:2:2", "\"duration\" is given twice"}},
      {"simulate " +
           file("twice_nested.json",
                scene(R"("params": {"k_bend": 1, "radius": 0.1, "k_bend": 2})")) +
           " --out {OUT}",
       {"params.k_bend", "given twice"}},
      // the parser's words translated, with file, line and column
      {"simulate " + file("syntax.json", "{\n  \"yarns\": [\n    tru\n  ]\n}\n") + " --out {OUT}",
       {"syntax.json:3:", "malformed JSON", "invalid literal", "last read: 'tru'"},
       false,
       {"parse error at", "syntax error while"}},
      {"simulate " + file("binary.json", binary) + " --out {OUT}",
       {"binary.json:1:", "malformed JSON"}},
      {"simulate " + file("empty.json", "") + " --out {OUT}", {"empty.json", "malformed JSON"}},
      {"simulate " + file("cut.json", R"({"yarns": [{"line": )") + " --out {OUT}",
       {"cut.json:1:", "unexpected end of input"}},
      // stretch: a fit to pulls too short to measure a stiffness
      {"stretch --from " + KNIT + " --sheet --fit " + runs + "/course," + runs + "/wale," + runs +
           "/bias --out {OUT}",
       {"--fit " + runs + "/course", "pull further (--to 0.3 or more)", "pulled to 0.05"}},
      {"stretch --from " + KNIT + " --sheet --fit " + runs + "/typed --out {OUT}",
       {"--fit " + runs + "/typed", "not a stretch run's"}},
      // --plot: no "wrote" before a failure; a PNG only under a .png name
      {"stretch " + (dir() / "curves/run").string() + " --plot {OUT}.txt",
       {"--plot", "name it .png"},
       false,
       {"wrote"}},
      {"stretch " + (dir() / "no_such_run").string() + " --plot {OUT}.png",
       {"no_such_run/stretch.csv"},
       false,
       {"wrote"}},
      {"stretch --from " + KNIT + " --to 20 --out {OUT}", {"--to", "20"}},
      {"stretch --from " + KNIT + " --speed 0 --out {OUT}", {"--speed"}},
      // plot: bad CSVs named by line, their bytes shown escaped and short
      {"plot " + file("binary.csv", "x,y\n1," + binary + std::string(5000, 'z') + "\n"),
       {"binary.csv: line 2", "column 'y'", "\\xFF\\xFE"}},
      {"plot " + file("words.csv", "x,y\n1,2\n3,abc\n"),
       {"words.csv: line 3", "'abc' is not a number"}},
      {"plot " + file("one_column.csv", "x\n1\n2\n"), {"one_column.csv", "at least two columns"}},
      {"plot " + file("header.csv", "x,y\n"), {"header.csv", "no data rows"}},
      {"plot " + file("good.csv", "x,y\n1,2\n2,3\n") + " --out {OUT}.txt", {"{OUT}.txt", ".png"}},
      {"plot /dev/zero", {"/dev/zero", "not a regular file"}},

      // ---- what already passed: kept passing ----
      // charts
      {"relax " + file("bad.chart", "kp\nkx\n") + " --out {OUT}",
       {"bad.chart:2:2", "unknown stitch 'x'"}},
      {"relax " + file("ragged.chart", "kpk\nkp\n") + " --out {OUT}",
       {"ragged.chart:2", "row has 2"}},
      {"relax " + file("empty.chart", "# nothing\n\n") + " --out {OUT}",
       {"empty.chart", "empty chart"}},
      {"relax " + file("utf8.chart", "kp\nk\xc3\xa9\n") + " --out {OUT}",
       {"utf8.chart:2:2", "byte 0xC3"}},
      {"relax no_such_pattern --out {OUT}", {"no_such_pattern", "not a built-in pattern"}},
      // knitout
      {"relax " + file("rack.k", swatch(14, "rack 40")) + " --out {OUT}",
       {"rack.k:14: 'rack 40'", "racking"}},
      {"relax " + file("nothing.k", ";!knitout-2\nin 3\n") + " --out {OUT}",
       {"nothing.k:2", "no stitches"}},
      {"relax " + file("not_knitout.k", "knit + f1 3\n") + " --out {OUT}",
       {"not_knitout.k:1", "not a knitout program"}},
      {"relax " + file("carriers.k", swatch(15, "knit + f49 2")) + " --out {OUT}",
       {"carriers.k:15: 'knit + f49 2'", "carrier 2 is not in"}},
      // scenes
      {"simulate " + file("unknown.json", scene(R"("gravty": [0,0,-981])")) + " --out {OUT}",
       {"gravty", "unknown key"}},
      {"simulate " + file("gravity.json", scene(R"("gravity": "down")")) + " --out {OUT}",
       {"gravity", "expected an array"}},
      {"simulate " + file("every.json", scene(R"("output_every": 0)")) + " --out {OUT}",
       {"output_every", "got 0"}},
      {"simulate " + file("pin_yarn.json", scene(R"("pins": [{"yarn": 3, "at": "start"}])")) +
           " --out {OUT}",
       {"pins[0].yarn", "does not exist"}},
      {"simulate " + file("bad_state.json", R"({"knits": [{"state": "no_such.kstate"}]})") +
           " --out {OUT}",
       {"knits[0].state", "no_such.kstate"}},
      // .kstate bytes
      {"export " + file("random.kstate", binary + std::string(300, '\x07')) +
           " --format obj --out {OUT}.obj",
       {"random.kstate"}},
      {"export " + file("empty.kstate", "") + " --format obj --out {OUT}.obj", {"empty.kstate"}},
      {"render " + (dir() / "random.kstate").string() + " --out {OUT}.png", {"random.kstate"}},
      {"view " + (dir() / "random.kstate").string() + " --out {OUT}.html", {"random.kstate"}},
      {"stretch --from " + (dir() / "random.kstate").string() + " --out {OUT}", {"random.kstate"}},
      {"simulate " + file("random_knit.json", R"({"knits": [{"state": "random.kstate"}]})") +
           " --out {OUT}",
       {"knits[0].state", "random.kstate"}},
      // missing files
      {"simulate " + (dir() / "nope.json").string() + " --out {OUT}", {"nope.json"}, true},
      {"export " + (dir() / "nope.kstate").string() + " --format obj --out {OUT}.obj",
       {"nope.kstate"},
       true},
      {"plot " + (dir() / "nope.csv").string(), {"nope.csv"}, true},
      {"relax --from " + (dir() / "nope.yarns").string() + " --out {OUT}", {"nope.yarns"}, true},
      {"view " + (dir() / "nope").string() + " --out {OUT}.html", {"nope"}, true},
      // bad options
      {"simulate " + PENDULUM + " --duration abc --out {OUT}", {"--duration"}, true},
      {"simulate " + PENDULUM + " --duration 1e400 --out {OUT}", {"--duration"}, true},
      {"simulate " + PENDULUM + " --threads -1 --out {OUT}", {"--threads"}, true},
      {"relax stockinette --threads 99999 --out {OUT}", {"--threads"}, true},
      {"simulate " + PENDULUM + " --frobnicate --out {OUT}", {"--frobnicate"}, true},
      {"relax stockinette --rows abc --out {OUT}", {"--rows"}, true},
      {"relax stockinette --rows 4 --cols 4 --time-step 0 --out {OUT}", {"--time-step"}, true},
      {"simulate " + PENDULUM + " --output-every 0 --out {OUT}", {"--output-every"}, true},
      {"export " + KNIT + " --format xyz --out {OUT}.xyz", {"--format"}, true},
      {"render " + KNIT + " --size 10 --out {OUT}.png", {"10"}},
      {"frobnicate", {"frobnicate"}, true},
  };
}

// what a message never shows: a library's own words, or a crash's
const std::vector<std::string> LIBRARY_WORDS = {
    "json.exception", "filesystem error", "std::",   "what():", "terminate called",
    "basic_string",   "Segmentation",     "Aborted", "stoi",    "stod"};

TEST(HostileInput, EveryBadInputIsRefusedByNameWithNothingLeftBehind) {
  const std::vector<Case> table = cases();
  for (size_t k = 0; k < table.size(); ++k) {
    const Case& c = table[k];
    const std::string out = (dir() / ("out_" + std::to_string(k))).string();
    std::string args = c.args;
    for (size_t at; (at = args.find("{OUT}")) != std::string::npos;) args.replace(at, 5, out);
    const Result r = run(args);
    SCOPED_TRACE("knitsim " + args + "\n" + r.output.substr(0, 600));
    if (c.usage) {
      EXPECT_GT(r.code, 0);
      EXPECT_LT(r.code, 128) << "ended by a signal";
    } else {
      EXPECT_EQ(r.code, 1);
    }
    for (std::string name : c.names) {
      for (size_t at; (at = name.find("{OUT}")) != std::string::npos;) name.replace(at, 5, out);
      EXPECT_NE(r.output.find(name), std::string::npos) << "not named: " << name;
    }
    for (const std::string& word : c.not_said)
      EXPECT_EQ(r.output.find(word), std::string::npos) << "said: " << word;
    for (const std::string& word : LIBRARY_WORDS)
      EXPECT_EQ(r.output.find(word), std::string::npos) << "library text: " << word;
    EXPECT_LT(r.output.size(), 2000u) << "a message should be short";
    // no raw bytes of the input: control characters (but the line ends) and bytes that are
    // not UTF-8 text (the escape sequence \x1b[31m would recolour the terminal)
    for (const unsigned char ch : r.output)
      EXPECT_FALSE(ch < 0x20 && ch != '\n' && ch != '\t') << "raw byte " << int(ch);
    EXPECT_EQ(r.output.find('\xff'), std::string::npos) << "raw byte 0xff";
    // nothing written under the case's output name, nor a temporary beside the inputs
    const std::string mine = "out_" + std::to_string(k);
    for (const auto& e : fs::directory_iterator(dir())) {
      const std::string name = e.path().filename().string();
      EXPECT_FALSE(name == mine || name.rfind(mine + ".", 0) == 0) << "left behind: " << name;
      EXPECT_NE(e.path().extension(), ".tmp") << "a temporary left behind: " << name;
    }
  }
}

}  // namespace
