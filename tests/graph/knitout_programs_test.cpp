// Real knitting-machine programs (tests/data/knitout: textiles-lab's public-domain
// knitout examples; tests/data/yarns: the smobj tools' .k programs and the .yarns they
// made) run on the machine model. Each builds a graph that passes the graph's checks,
// with as many loops as the program has stitch instructions (counted here by a regular
// expression, one loop per carrier), and exactly the free loops its last courses leave.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "knit/graph/knitout_machine.hpp"

namespace knit::graph {
namespace {

const std::string DATA = std::string(KNIT_TEST_DATA);

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> words(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// what a program's text says, read line by line with regular expressions (independent of
// the interpreter): its stitch lines (knit, purl, tuck, split with at least one carrier)
// and the loops they make (one per carrier); and which needles hold yarn — a stitch fills
// its needle, a transfer moves that to the other needle, a drop (or a knit without yarn)
// empties it. A loop on a needle is held by nothing until a knit there pulls a new loop
// through it, so the needles still filled at the end and those emptied by a drop each
// hold loops that are free at the end.
struct Census {
  std::size_t loops = 0;
  std::set<int> stitch_lines;
  std::size_t drops = 0;
  std::size_t filled_needles_dropped = 0;
  std::size_t filled_needles_at_end = 0;
};

Census census(const std::string& text) {
  static const std::regex stitch(R"(^\s*(knit|purl|tuck)\s+([+-])\s+([fb]-?\d+)([^;]*))");
  static const std::regex split(R"(^\s*split\s+([+-])\s+([fb]-?\d+)\s+([fb]s?-?\d+)([^;]*))");
  static const std::regex xfer(R"(^\s*xfer\s+([fb]s?-?\d+)\s+([fb]s?-?\d+))");
  static const std::regex drop(R"(^\s*(drop\s+([fb]-?\d+)|knit\s+[+-]\s+([fb]-?\d+)\s*(;|$)))");
  Census c;
  std::map<std::string, bool> filled;
  std::istringstream in(text);
  int line_no = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::smatch m;
    if (std::regex_search(line, m, drop)) {
      ++c.drops;
      const std::string n = m[2].matched ? m[2].str() : m[3].str();
      if (filled[n]) ++c.filled_needles_dropped;
      filled[n] = false;
      continue;
    }
    if (std::regex_search(line, m, xfer)) {
      if (filled[m[1]]) filled[m[2]] = true;
      filled[m[1]] = false;
      continue;
    }
    std::string cs;
    if (std::regex_search(line, m, stitch)) {
      cs = m[4];
      if (!words(cs).empty()) filled[m[3]] = true;
    } else if (std::regex_search(line, m, split)) {
      cs = m[4];
      if (filled[m[2]]) filled[m[3]] = true;
      filled[m[2]] = !words(cs).empty();
    }
    const std::size_t carriers = words(cs).size();
    if (carriers == 0) continue;
    c.loops += carriers;
    c.stitch_lines.insert(line_no);
  }
  for (const auto& [n, f] : filled) c.filled_needles_at_end += f;
  return c;
}

std::vector<std::string> programs() {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(DATA + "/knitout")) {
    const std::string ext = e.path().extension().string();
    if (ext == ".k" || ext == ".knitout") out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(KnitoutPrograms, EveryProgramBuildsAGraphThatPassesTheChecks) {
  const std::vector<std::string> files = programs();
  ASSERT_EQ(files.size(), 24u);
  std::size_t total = 0;
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    KnitoutResult r;
    ASSERT_NO_THROW(r = load_knitout_graph(path));
    const KnitGraph& g = r.graph;
    const Census c = census(slurp(path));
    // one loop per carrier of every stitch instruction
    EXPECT_EQ(g.num_loops(), c.loops);
    total += g.num_loops();
    const GraphCheck check = g.check();
    EXPECT_TRUE(check.ok()) << (check.problems.empty() ? "" : check.problems[0]);
    // every yarn in the program was taken out again
    for (const Yarn& y : g.yarns()) EXPECT_GT(y.out_line, 0) << "carrier " << y.carrier;
    // free loops: one on each needle still filled at the end or emptied by a drop (the
    // programs end with a whole course, or drop one, or bind off leaving its tail and the
    // tucks that held the chain)
    EXPECT_EQ(check.free_live.size(), c.filled_needles_at_end);
    EXPECT_EQ(check.ladders.size(), c.filled_needles_dropped);
    if (c.drops == 0) {
      EXPECT_TRUE(check.ladders.empty());
    }
    for (LoopId l : check.ladders) EXPECT_EQ(g.loop(l).end, LoopEnd::DROPPED);
    // nothing ladders in the middle of the piece: a free loop dropped before the program's
    // last stitch is on a needle away from the piece's top course (the one dropped at the
    // end), as the little swatches that start intarsia's yarns on needles beside the piece
    const int last_stitch = *c.stitch_lines.rbegin();
    std::set<std::pair<Bed, int>> top;
    for (LoopId l : check.ladders)
      if (g.loop(l).end_line > last_stitch) top.insert({g.loop(l).bed, g.loop(l).needle});
    for (LoopId l : check.ladders)
      if (g.loop(l).end_line < last_stitch) {
        EXPECT_EQ(top.count({g.loop(l).bed, g.loop(l).needle}), 0u)
            << "loop " << l << " made at line " << g.loop(l).line << " ladders the piece";
      }
  }
  // the README's "about 129k stitches in all"
  EXPECT_GT(total, 120000u);
  EXPECT_LT(total, 140000u);
}

TEST(KnitoutPrograms, WasteYarnProgramsDropTheirLastCourseAsALadder) {
  const KnitoutResult r = load_knitout_graph(DATA + "/knitout/basic-vol-1_singlejersey.knitout");
  const GraphCheck c = r.graph.check();
  EXPECT_TRUE(c.free_live.empty());
  ASSERT_FALSE(c.ladders.empty());
  // every ladder was dropped by a drop instruction, on the needle it was last made on
  const std::vector<std::string> lines = [&] {
    std::vector<std::string> v;
    std::istringstream in(slurp(DATA + "/knitout/basic-vol-1_singlejersey.knitout"));
    for (std::string l; std::getline(in, l);) v.push_back(l);
    return v;
  }();
  for (LoopId l : c.ladders) {
    const Loop& loop = r.graph.loop(l);
    const std::string& drop = lines[static_cast<std::size_t>(loop.end_line - 1)];
    EXPECT_EQ(drop, "drop " + needle_name(loop.bed, loop.needle)) << l;
  }
}

TEST(KnitoutPrograms, TransferProgramsMakePurlsOnTheBackBed) {
  // garter: every course is moved to the other bed and knit there
  const KnitoutResult r = load_knitout_graph(DATA + "/knitout/Tutorial3_garter.k");
  std::map<int, std::set<Face>> faces_of_course;
  for (const Loop& l : r.graph.loops())
    if (l.kind == LoopKind::KNIT) faces_of_course[l.course].insert(l.face);
  int knit_courses = 0, purl_courses = 0;
  for (const auto& [course, faces] : faces_of_course) {
    EXPECT_EQ(faces.size(), 1u) << "course " << course << " mixes knits and purls";
    (*faces.begin() == Face::KNIT ? knit_courses : purl_courses) += 1;
  }
  EXPECT_GT(knit_courses, 10);
  EXPECT_NEAR(knit_courses, purl_courses, 1);
}

TEST(KnitoutPrograms, DecreasesStackTwoLoops) {
  const KnitoutResult r = load_knitout_graph(DATA + "/knitout/decrease.knitout");
  std::size_t two = 0;
  for (const Loop& l : r.graph.loops()) {
    EXPECT_LE(l.parent_count, 3u);
    if (l.parent_count >= 2) ++two;
  }
  EXPECT_GT(two, 0u);
  // the piece narrows: fewer loops in the last course than in the first knitted one
  std::map<int, int> per_course;
  for (const Loop& l : r.graph.loops())
    if (l.kind == LoopKind::KNIT) ++per_course[l.course];
  EXPECT_LT(per_course.rbegin()->second, per_course.begin()->second);
}

TEST(KnitoutPrograms, IntarsiaAndStripesKeepEachCarriersLoopsOnItsYarn) {
  for (const char* name : {"intarsia.knitout", "sheet-stripes.knitout"}) {
    SCOPED_TRACE(name);
    const KnitoutResult r = load_knitout_graph(DATA + "/knitout/" + name);
    std::set<std::string> carriers;
    for (const Yarn& y : r.graph.yarns()) {
      carriers.insert(y.carrier);
      for (const YarnStep& s : y.steps) {
        if (s.kind != YarnStep::LOOP) continue;
        EXPECT_EQ(r.graph.yarns()[static_cast<std::size_t>(r.graph.loop(s.loop).yarn)].carrier,
                  y.carrier);
      }
    }
    EXPECT_EQ(carriers.size(), std::string(name) == "intarsia.knitout" ? 3u : 2u);
  }
}

TEST(KnitoutPrograms, QuarterPitchRibsKnitBothBeds) {
  const KnitoutResult r = load_knitout_graph(DATA + "/knitout/basic-vol-1_interlock.knitout");
  std::size_t front = 0, back = 0;
  for (const Loop& l : r.graph.loops()) (l.bed == Bed::FRONT ? front : back) += 1;
  EXPECT_GT(front, 1000u);
  EXPECT_GT(back, 1000u);
  EXPECT_TRUE(r.graph.check().ok());
}

// the .yarns the smobj tools made from the four .k programs record, per point, the source
// line of the stitch that made it: the graph has a loop for exactly those lines
std::set<int> yarns_source_lines(const std::string& path) {
  const std::string b = slurp(path);
  std::set<int> lines;
  std::size_t p = 0;
  while (p + 8 <= b.size()) {
    const std::string magic = b.substr(p, 4);
    std::uint32_t n = 0;
    std::memcpy(&n, b.data() + p + 4, 4);
    if (magic == "src.")
      for (std::size_t k = 0; k + 4 <= n; k += 4) {
        std::uint32_t v = 0;
        std::memcpy(&v, b.data() + p + 8 + k, 4);
        if (v != 0) lines.insert(static_cast<int>(v));
      }
    p += 8 + n;
  }
  return lines;
}

TEST(KnitoutPrograms, TheSmobjProgramsHaveALoopForEveryStitchTheirYarnsShow) {
  for (const char* name :
       {"swatch4x4", "swatch4x4garter", "swatch6x8doublemoss", "swatch12x8ribbing"}) {
    SCOPED_TRACE(name);
    const std::string k = DATA + "/yarns/" + name + ".k";
    const KnitoutResult r = load_knitout_graph(k);
    std::set<int> loop_lines;
    for (const Loop& l : r.graph.loops()) loop_lines.insert(l.line);
    const std::set<int> shown = yarns_source_lines(DATA + "/yarns/" + name + ".yarns");
    EXPECT_EQ(loop_lines, shown);
    EXPECT_EQ(loop_lines, census(slurp(k)).stitch_lines);
    const GraphCheck c = r.graph.check();
    EXPECT_TRUE(c.ok());
    EXPECT_EQ(c.free_live.size(), census(slurp(k)).filled_needles_at_end);
  }
  // garter from `purl`: the purl courses show their purl side
  const KnitoutResult g = load_knitout_graph(DATA + "/yarns/swatch4x4garter.k");
  std::size_t purls = 0;
  for (const Loop& l : g.graph.loops()) purls += l.face == Face::PURL;
  std::size_t purl_lines = 0;
  std::istringstream in(slurp(DATA + "/yarns/swatch4x4garter.k"));
  for (std::string l; std::getline(in, l);) purl_lines += l.rfind("purl ", 0) == 0;
  EXPECT_GT(purl_lines, 0u);
  EXPECT_EQ(purls, purl_lines);
}

}  // namespace
}  // namespace knit::graph
