// Knitout programs read through the knit graph (the machine model, src/knit/graph) into the
// chart and size the generator knits, and everything the generator cannot lay refused with
// the line and instruction.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>

#include "knit/contact/crossings.hpp"
#include "knit/graph/knitout_machine.hpp"
#include "knit/pattern/generator.hpp"
#include "knit/pattern/knitout.hpp"
#include "knit/recipes/relax_knit.hpp"

namespace knit {
namespace {

const std::string YARNS = std::string(KNIT_TEST_DATA) + "/yarns/";

std::string rows_of(const KnitoutPiece& p) {
  std::string out;
  for (int r = p.rows() - 1; r >= 0; --r) out += p.pattern.rows[r] + (r ? "/" : "");
  return out;
}

std::string refusal(const std::string& program) {
  try {
    parse_knitout(program, "prog.k");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(accepted)";
}

// a flat program: cast on needles 1..n with tucks, then `rows` passes of `stitch` ops
std::string flat(int n, const std::vector<std::string>& rows) {
  std::string s = ";!knitout-2\n;;Carriers: 1 2 3\ninhook 3\n";
  for (int k = n; k >= 1; --k) s += "tuck - f" + std::to_string(k) + " 3\n";
  s += "releasehook 3\n";
  for (size_t r = 0; r < rows.size(); ++r) {
    const bool right = r % 2 == 0;
    for (int k = 0; k < n; ++k) {
      const int needle = right ? k + 1 : n - k;
      const char st = rows[r][static_cast<size_t>(needle - 1)];
      // 'k': knit on the front bed, 'p': purl on the front bed, 'b': knit on the back bed
      const std::string op = st == 'k' ? "knit" : st == 'p' ? "purl" : "knit";
      const std::string bed = st == 'b' ? "b" : "f";
      s += op + (right ? " + " : " - ") + bed + std::to_string(needle) + " 3\n";
    }
  }
  return s + "outhook 3\n";
}

TEST(Knitout, TheShippedSwatchesReadAsTheirCharts) {
  const KnitoutPiece st = load_knitout(YARNS + "swatch4x4.k");
  EXPECT_FALSE(st.in_the_round);
  EXPECT_EQ(rows_of(st), "kkkk/kkkk/kkkk/kkkk");
  // garter: the program purls every second row
  EXPECT_EQ(rows_of(load_knitout(YARNS + "swatch4x4garter.k")), "pppp/kkkk/pppp/kkkk");
  // the "ribbing" program knits one and purls one, starting each pass with a knit at the
  // needle it turns on: read as a machine knits it (the front bed always faces the front),
  // its columns alternate k and p from row to row, a seed stitch, 12 stitches by 8 rows
  const KnitoutPiece rib = load_knitout(YARNS + "swatch12x8ribbing.k");
  ASSERT_EQ(rib.rows(), 8);
  ASSERT_EQ(rib.cols(), 12);
  for (int r = 0; r < 8; ++r)
    EXPECT_EQ(rib.pattern.rows[r], r % 2 ? "pkpkpkpkpkpk" : "kpkpkpkpkpkp") << r;
  // double moss: k2 p2, shifted by two every second row
  const KnitoutPiece moss = load_knitout(YARNS + "swatch6x8doublemoss.k");
  EXPECT_EQ(moss.rows(), 8);
  EXPECT_EQ(moss.cols(), 6);
  EXPECT_EQ(moss.pattern.rows[0], "kkppkk");
  EXPECT_EQ(moss.pattern.rows[1], "kkppkk");
  EXPECT_EQ(moss.pattern.rows[2], "ppkkpp");
}

TEST(Knitout, BackBedStitchesArePurlsSeenFromTheFront) {
  // a V-bed rib: knit on the front bed for the knit columns, on the back bed for the purls
  const KnitoutPiece p = parse_knitout(flat(4, {"kbkb", "kbkb", "kbkb"}), "rib.k");
  EXPECT_FALSE(p.in_the_round);
  EXPECT_EQ(rows_of(p), "kpkp/kpkp/kpkp");
}

TEST(Knitout, PurlsMadeByTransfersReadAsPurls) {
  // a machine purls a stitch by moving its loop to the back bed, knitting it there and
  // moving it back: the same fabric as the back-bed stitches of flat(), seen from the front
  std::string s = ";!knitout-2\nin 3\n";
  for (int k = 1; k <= 4; ++k) s += "knit + f" + std::to_string(k) + " 3\n";
  s += "xfer f2 b2\nxfer f4 b4\n";
  s += "knit - b4 3\nknit - f3 3\nknit - b2 3\nknit - f1 3\n";
  s += "xfer b2 f2\nxfer b4 f4\n";
  for (int k = 1; k <= 4; ++k) s += "knit + f" + std::to_string(k) + " 3\n";
  s += "out 3\n";
  const KnitoutPiece p = parse_knitout(s, "xfer.k");
  EXPECT_FALSE(p.in_the_round);
  EXPECT_EQ(rows_of(p), "kkkk/kpkp/kkkk");
  // racked transfers that bring each loop back to its own column change nothing
  std::string r =
      ";!knitout-2\nin 3\nknit + f1 3\nknit + f2 3\nxfer f2 b2\nrack 1\n"
      "xfer b2 f3\nrack 0\nxfer f3 b3\nrack -1\nxfer b3 f2\nrack 0\n"
      "knit - f2 3\nknit - f1 3\n";
  EXPECT_EQ(rows_of(parse_knitout(r, "racked.k")), "kk/kk");
}

TEST(Knitout, AProgramWhoseFirstRowGoesLeftIsLaidFromTheRight) {
  // a 1×1 rib knit on both beds, the first pass from the right (as every textiles-lab
  // program does): the same chart as from the left, the yarn entering at the right edge
  std::string s = ";!knitout-2\nin 3\n";
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 6; ++k) {
      const int n = r % 2 == 0 ? 6 - k : k + 1;
      s += std::string("knit ") + (r % 2 == 0 ? "- " : "+ ") + (n % 2 ? "f" : "b") +
           std::to_string(n) + " 3\n";
    }
  const KnitoutPiece p = parse_knitout(s, "left.k");
  EXPECT_TRUE(p.pattern.first_row_leftward);
  EXPECT_EQ(rows_of(p), "kpkpkp/kpkpkp/kpkpkp/kpkpkp");
  KnitOptions o;
  o.rows = 4;
  o.cols = 6;
  const GeneratedKnit left = generate_knit(p.pattern, o);
  Pattern right_pattern = p.pattern;
  right_pattern.first_row_leftward = false;
  const GeneratedKnit right = generate_knit(right_pattern, o);
  // the yarn's first stitch is the rightmost column's, on the right (x > 0), and the last
  // row (row 3, knit from the left) ends at the right edge too
  int first = 0;
  while (left.piece[first] != YarnPiece::STITCH) ++first;
  EXPECT_EQ(left.stitch[first].col, 5);
  EXPECT_EQ(left.stitch[first].row, 0);
  EXPECT_GT(left.control_points.col(first + 2).x(), 0);
  EXPECT_LT(right.control_points.col(first + 2).x(), 0);
  EXPECT_EQ(left.stitch.back().col, 5);
  // the same stitches: in row 1 the knit columns' yarn lies in front of the purl columns'
  // beside them (the legs of a rib's columns sit towards the face they show), from either
  // side; the fits differ a little (the yarn is fitted in the order it runs)
  auto mean_z = [&](const GeneratedKnit& g, int col) {
    double z = 0;
    int n = 0;
    for (int i = 0; i < g.num_segments(); ++i)
      if (g.piece[i] == YarnPiece::STITCH && g.stitch[i].col == col && g.stitch[i].row == 1) {
        z += g.control_points.col(i + 1).z();
        ++n;
      }
    return z / n;
  };
  for (const GeneratedKnit* g : {&left, &right})
    for (int c = 0; c + 1 < 6; ++c) {
      const double front = mean_z(*g, c) - mean_z(*g, c + 1);
      EXPECT_GT(c % 2 == 0 ? front : -front, 0.05) << (g == &left ? "left" : "right") << " " << c;
    }
  EXPECT_GT(left.min_distance_ratio, 0.85);
}

TEST(Knitout, ACastOnKnitInTwoPassesIsNotARow) {
  // as machines cast on: every other needle from the right, the others back from the left,
  // then two rows over them all
  const std::string s =
      ";!knitout-2\nin 3\nknit - f4 3\nknit - f2 3\nknit + f1 3\nknit + f3 3\n"
      "knit - f4 3\nknit - f3 3\nknit - f2 3\nknit - f1 3\n"
      "knit + f1 3\nknit + f2 3\nknit + f3 3\nknit + f4 3\n";
  const KnitoutPiece p = parse_knitout(s, "castOn.k");
  EXPECT_EQ(p.rows(), 2);
  EXPECT_EQ(p.cols(), 4);
  EXPECT_TRUE(p.pattern.first_row_leftward);
  // one pass on empty needles is a row of stitches of its own
  const std::string one = ";!knitout-2\nin 3\nknit - f2 3\nknit - f1 3\nknit + f1 3\nknit + f2 3\n";
  EXPECT_EQ(parse_knitout(one, "one.k").rows(), 2);
}

TEST(Knitout, ARibCastOnsLastTuckIsItsColumnsFirstStitch) {
  // a 1×1 rib cast on alternate beds from the right; the first row goes back from f2,
  // beside the last tuck (b1), without knitting it; the second row ends on b1
  const std::string head =
      ";!knitout-2\nin 3\ntuck - f4 3\ntuck - b3 3\ntuck - f2 3\ntuck - b1 3\n";
  const std::string rows =
      "knit + f2 3\nknit + b3 3\nknit + f4 3\n"
      "knit - f4 3\nknit - b3 3\nknit - f2 3\nknit - b1 3\n";
  const KnitoutPiece p = parse_knitout(head + rows, "rib.k");
  EXPECT_EQ(rows_of(p), "pkpk/pkpk");
  EXPECT_FALSE(p.pattern.first_row_leftward);
  // not beside the first needle (the row starts at f4 after a tuck on b1), not on the
  // carrier that knits, or knit by the first row itself: a late column as before
  const std::string far =
      ";!knitout-2\nin 3\ntuck - f4 3\ntuck - b3 3\ntuck - f2 3\ntuck - b1 3\n"
      "knit - f4 3\nknit - b3 3\nknit - f2 3\nknit + b1 3\n";
  EXPECT_NE(refusal(far).find("a new column"), std::string::npos) << refusal(far);
  const std::string knit_first = head + "knit + b1 3\nknit + f2 3\nknit + b3 3\nknit + f4 3\n";
  EXPECT_EQ(rows_of(parse_knitout(knit_first, "rib.k")), "pkpk");
}

TEST(Knitout, ATubeOnBothBedsIsKnitInTheRound) {
  std::string s = ";!knitout-2\nin 5\n";
  for (int r = 0; r < 3; ++r) {
    for (int k = 1; k <= 4; ++k) s += "knit + f" + std::to_string(k) + " 5\n";
    for (int k = 4; k >= 1; --k)
      s += (r == 1 ? "purl - b" : "knit - b") + std::to_string(k) + " 5\n";
  }
  s += "out 5\n";
  const KnitoutPiece p = parse_knitout(s, "tube.k");
  EXPECT_TRUE(p.in_the_round);
  ASSERT_EQ(p.cols(), 8);
  // seen from outside, a knit on either bed is a knit; the purls of round 1's back half
  EXPECT_EQ(rows_of(p), "kkkkkkkk/kkkkpppp/kkkkkkkk");
}

TEST(Knitout, WhatCannotBeKnitYetIsRefusedWithItsLine) {
  const std::string head = ";!knitout-2\nin 3\nknit + f1 3\nknit + f2 3\n";
  struct Case {
    std::string program, expect;
  };
  const std::vector<Case> cases = {
      {"knit + f1 3\n", "prog.k:1: not a knitout program"},
      // transfers and racking that leave one loop per column are read (a machine's purls)
      {head + "xfer f1 b1\nknit - f2 3\nknit - b1 3\n", "(accepted)"},
      {head + "xfer f1 b1\nknit - b1 3\nknit - f2 3\n",
       "prog.k:6: 'knit - b1 3': row 1 starts at the edge where row 0 started"},
      {head + "rack 1\n", "(accepted)"},
      {head + "rack 0\nknit - f2 3\nknit - f1 3\n", "(accepted)"},
      // a last row of loops dropped off the needles, as a program ends: its top edge
      {head + "drop f1\ndrop f2\n", "(accepted)"},
      // what needs the knit graph's own layout
      {head + "split + f1 b1 3\n", "prog.k:5: 'split + f1 b1 3': a split"},
      {head + "in 4\nknit - f2 4\nknit - f1 3\n",
       "prog.k:7: 'knit - f1 3': row 1 is knit by two yarns (carriers 4 and 3): intarsia"},
      // stripes: carrier 3 goes on from where it stopped, at f2; not from f1
      {head + "in 4\nknit - f2 4\nknit - f1 4\nknit - f2 3\nknit - f1 3\n", "(accepted)"},
      {head + "in 4\nknit - f2 4\nknit - f1 4\nknit + f1 3\nknit + f2 3\n",
       "prog.k:8: 'knit + f1 3': row 2 starts at the edge where row 0 started (both knit by "
       "carrier 3)"},
      {head + "tuck - f2 3\n", "prog.k:5: 'tuck - f2 3': a tuck beside the loops"},
      {head + "xfer f2 b2\nrack -1\nxfer b2 f1\nrack 0\nknit - f1 3\n",
       "prog.k:9: 'knit - f1 3': a decrease (2 loops pulled through at once)"},
      {head + "xfer f2 b2\nrack -1\nxfer b2 f1\nrack 0\nknit - f2 3\nknit - f1 3\n",
       "prog.k:9: 'knit - f2 3': a new column (a loop on an empty needle) after the first row"},
      // what the machine refuses (the interpreter, src/knit/graph/knitout_machine.hpp)
      {head + "knit - f2 4\n", "prog.k:5: 'knit - f2 4': carrier 4 is not in"},
      {head + "knit - f2\n", "(accepted)"},  // a knit with no carrier drops (knitout-2)
      {head + "knit - fs2 3\n", "sliders"},
      {head + "knit - x2 3\n", "expected a needle such as f12"},
      {head + "knit ^ f2 3\n", "expected a direction"},
      {head + "frobnicate\n", "prog.k:5: 'frobnicate': unknown"},
      // pieces that are not rectangles
      {head + "knit - f2 3\n", "prog.k:5: 'knit - f2 3': row 1 has 1 of the piece's 2 stitches"},
      {head + "knit - f2 3\nknit - f2 3\n", "prog.k:5: 'knit - f2 3': row 1 has 1 of"},
      {";!knitout-2\nin 3\n", "prog.k:2: 'in 3': the program knits no stitches"},
      // a first pass on the front bed and a second on the back: a tube of three columns
      {";!knitout-2\nin 3\nknit + f1 3\nknit + f2 3\nknit - b1 3\n", "(accepted)"},
  };
  for (const Case& c : cases) {
    const std::string got = refusal(c.program);
    EXPECT_NE(got.find(c.expect), std::string::npos) << c.program << "\n→ " << got;
  }
  // a mistyped needle (f-3 for f1, a column of its own) is named on its own line, not on
  // the rows it shifts; a row that starts inside the piece (f2 knit twice, f1 at the end
  // of the next pass) is named at its start
  const std::string three = ";!knitout-2\nin 3\n";
  std::string typo = three, inside = three;
  for (int r = 0; r < 4; ++r)
    for (int k = 1; k <= 3; ++k) {
      const int needle = r % 2 == 0 ? k : 4 - k;
      const std::string dir = r % 2 == 0 ? "+" : "-";
      typo += "knit " + dir + " f" + (r == 1 && k == 3 ? "-3" : std::to_string(needle)) + " 3\n";
      inside += "knit " + dir + " f" + std::to_string(r == 2 && k == 1 ? 2 : needle) + " 3\n";
    }
  EXPECT_NE(refusal(typo).find("prog.k:8: 'knit - f-3 3': a new column (a loop on an empty "
                               "needle) after the first row"),
            std::string::npos)
      << refusal(typo);
  EXPECT_NE(refusal(inside).find("prog.k:9: 'knit + f2 3': row 2 is knit in 2 passes"),
            std::string::npos)
      << refusal(inside);
  // machine settings do not change what is knitted
  EXPECT_EQ(refusal(head + "x-stitch-number 5\npause\nstitch 30 40\nmiss - f3 3\n"), "(accepted)");
}

// The textiles-lab programs (tests/data/knitout) whose graph is a rectangle of whole rows,
// each knit by one yarn — fourteen of the 24 (one of them striped, two carriers) — read as
// sheets: every loop but the cast-on's a stitch of the chart, the purls their transfers
// make where the program's name says, the rib and seed patterns as their names say; each is
// laid as yarn with the yarns apart, and the smaller ones' first steps of relaxation pass
// no yarn through another. The others are refused naming a line of the program (what they
// need is the graph's own layout).
TEST(Knitout, TheTextilesLabProgramsOfWholeRowsReadAsSheets) {
  const std::string dir = std::string(KNIT_TEST_DATA) + "/knitout/";
  const std::set<std::string> sheets = {"Tutorial1_helloworld.k",
                                        "Tutorial3_garter.k",
                                        "Tutorial3_piqueribbing.k",
                                        "Tutorial3_wafflestitch.k",
                                        "k.knitout",
                                        "rectangle.knitout",
                                        "basic-vol-1_singlejersey.knitout",
                                        "basic-vol-1_rib-1x1.knitout",
                                        "basic-vol-1_rib-2x2.knitout",
                                        "image-kp-half-rib.k",
                                        "Tutorial2_rib1x1.k",
                                        "Tutorial3_seedstitch.k",
                                        "Tutorial3_irishmoss.k",
                                        "sheet-stripes.knitout"};
  int refused = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name == "README.md") continue;
    if (!sheets.count(name)) {
      try {
        load_knitout(entry.path().string());
        ADD_FAILURE() << name << " was read as a sheet";
      } catch (const std::invalid_argument& e) {
        // SOURCE:LINE: 'INSTRUCTION': …
        EXPECT_NE(std::string(e.what()).find(entry.path().string() + ":"), std::string::npos)
            << e.what();
        ++refused;
      }
      continue;
    }
    const KnitoutPiece p = load_knitout(entry.path().string());
    // every loop of the graph is a stitch of the sheet, but the cast-on's: the loops made
    // on empty needles before the first one knit through another, when tucked or made in
    // more than one pass
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const graph::KnitoutResult run = graph::run_knitout(text, name);
    size_t leading = 0, tucked = 0;
    std::set<int> passes;
    for (const graph::Loop& l : run.graph.loops()) {
      if (!run.graph.parents(l.id).empty()) break;
      ++leading;
      tucked += l.tucked;
      passes.insert(l.pass);
    }
    // (the rib programs cast on alternate beds and start their first row beside the last
    // tuck without knitting it: that loop is the first stitch of its column)
    const bool edge_tuck = name == "Tutorial2_rib1x1.k" || name == "Tutorial3_seedstitch.k" ||
                           name == "Tutorial3_irishmoss.k";
    const size_t cast_on = passes.size() > 1 ? leading : tucked - edge_tuck;
    EXPECT_EQ(static_cast<size_t>(p.rows() * p.cols()), run.graph.num_loops() - cast_on) << name;
    EXPECT_FALSE(p.in_the_round) << name;
    for (int r = 0; r < p.rows(); ++r) {
      const std::string& row = p.pattern.rows[r];
      if (name == "Tutorial3_garter.k")  // every second row purled (by transfers)
        EXPECT_EQ(row, std::string(p.cols(), r % 2 ? 'p' : 'k')) << name << " row " << r;
      if (name == "Tutorial1_helloworld.k" || name == "rectangle.knitout")
        EXPECT_EQ(row, std::string(p.cols(), 'k')) << name << " row " << r;
      // the rib and the seed and moss stitches: knit and purl alternate along every row,
      // the first column (the back bed's edge needle) a purl in the rib; seed stitch turns
      // them over every row (above two rows of rib), moss every second row
      for (int c = 0; c + 1 < p.cols() && edge_tuck; ++c)
        EXPECT_NE(row[c], row[c + 1]) << name << " row " << r << ": " << row;
      if (name == "Tutorial2_rib1x1.k") EXPECT_EQ(row[0], 'p') << name << " row " << r;
      if (name == "Tutorial3_seedstitch.k" && r > 1)  // (over two rows of rib)
        EXPECT_NE(row[0], p.pattern.rows[r - 1][0]) << name << " row " << r << "\n" << rows_of(p);
      if (name == "Tutorial3_irishmoss.k" && r > 0)
        EXPECT_EQ(row[0] != p.pattern.rows[r - 1][0], r % 2 == 0) << name << " row " << r;
    }
    // laid as yarn: the smaller ones relaxed for 0.005 s too, every step checked
    KnitOptions ko;
    ko.rows = p.rows();
    ko.cols = p.cols();
    const GeneratedKnit g = generate_knit(p.pattern, ko);
    EXPECT_GT(g.min_distance_ratio, 0.5) << name;
    if (p.rows() * p.cols() > 500) continue;
    RelaxKnitOptions o;
    o.knit = ko;
    o.run.max_time = 0.005;
    o.run.progress = false;
    o.run.check_crossings = true;
    const RelaxResult rr = relax_knit(entry.path().string(), o);
    ASSERT_EQ(rr.report.status, StepStatus::OK) << name << ": " << rr.report.message;
    EXPECT_EQ(rr.report.summary.at("crossings").at("count").get<long long>(), 0) << name;
  }
  EXPECT_EQ(refused, 10);
}

// Stripes: rows knit by two carriers, each going on from the edge where it stopped (so
// carried up the edge past the other's rows, on both edges, two carries overlapping on the
// left). The rows are laid by the yarn that knit them, the yarns apart; relaxed, no yarn
// passes through another, each row stays where it was knit, and the fabric is the fabric of
// the same stitches knit with one yarn: its size within 3 % of that one's.
TEST(Knitout, StripesKeepTheirYarnsWhereTheyWereKnit) {
  const int n = 8;
  const std::string carriers = "ABBAAABA";  // the carrier of each row, from the bottom
  auto program = [&](const std::string& by) {
    std::string s = ";!knitout-2\n;;Carriers: A B\nin A\n";
    for (int k = n; k >= 1; --k) s += "tuck - f" + std::to_string(k) + " A\n";
    std::map<char, bool> at_left = {{'A', true}, {'B', true}};
    bool b_in = false;
    for (char c : by) {
      if (c == 'B' && !b_in) s += "in B\n", b_in = true;
      const bool right = at_left[c];
      for (int k = 0; k < n; ++k)
        s += std::string("knit ") + (right ? "+ f" : "- f") +
             std::to_string(right ? k + 1 : n - k) + " " + c + "\n";
      at_left[c] = !right;
    }
    return s;
  };
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "knitsim-stripes";
  std::filesystem::create_directories(dir);
  const std::string striped = (dir / "stripes.k").string(), plain = (dir / "plain.k").string();
  std::ofstream(striped) << program(carriers);
  // one yarn, to and fro
  std::string one;
  for (int r = 0; r < n; ++r) one += 'A';
  std::ofstream(plain) << program(one);

  const KnitoutPiece p = load_knitout(striped);
  ASSERT_EQ(p.rows(), n);
  const std::vector<int> yarns = {0, 1, 1, 0, 0, 0, 1, 0};
  EXPECT_EQ(p.pattern.row_yarn, yarns);
  KnitOptions ko;
  ko.rows = ko.cols = n;
  const GeneratedKnit g = generate_knit(p.pattern, ko);
  ASSERT_EQ(g.num_yarns(), 2);
  EXPECT_GT(g.min_distance_ratio, 0.85);
  // every stitch's segments are its row's yarn's
  std::vector<int> yarn_of(g.num_segments());
  for (int i = 0, y = 0, end = g.yarn_segments[0]; i < g.num_segments(); ++i) {
    if (i == end) end += g.yarn_segments[++y];
    yarn_of[i] = y;
    if (g.piece[i] == YarnPiece::STITCH) ASSERT_EQ(y, yarns[g.stitch[i].row]) << "segment " << i;
  }
  // each yarn's two free ends are glued to that yarn, against the fabric
  ASSERT_EQ(g.glues.size(), 4u);
  for (size_t k = 0; k < g.glues.size(); ++k) {
    EXPECT_EQ(yarn_of[g.glues[k].a.segment], static_cast<int>(k / 2)) << "glue " << k;
    EXPECT_EQ(yarn_of[g.glues[k].b.segment], static_cast<int>(k / 2)) << "glue " << k;
    EXPECT_LT(g.glue_gap_cm[k], 6 * 0.125) << "glue " << k;
    EXPECT_NEAR((g.point(g.glues[k].a) - g.point(g.glues[k].b)).norm(), g.glue_gap_cm[k], 1e-12);
  }

  auto relax = [&](const std::string& path) {
    RelaxKnitOptions o;
    o.knit = ko;
    o.run.max_time = 0.02;
    o.run.progress = false;
    o.run.check_crossings = true;
    return relax_knit(path, o);
  };
  const RelaxResult s = relax(striped), u = relax(plain);
  ASSERT_EQ(s.report.status, StepStatus::OK) << s.report.message;
  ASSERT_EQ(u.report.status, StepStatus::OK) << u.report.message;
  EXPECT_EQ(s.report.summary.at("crossings").at("count").get<long long>(), 0);
  EXPECT_EQ(s.model.yarns.size(), 2u);
  // each row where it was knit: the rows' mean heights in order
  std::vector<double> y_sum(n, 0);
  std::vector<int> y_count(n, 0);
  for (int i = 0; i < g.num_segments(); ++i)
    if (g.piece[i] == YarnPiece::STITCH) {
      y_sum[g.stitch[i].row] += s.state.q[3 * (i + 3 * (i >= g.yarn_segments[0])) + 1];
      ++y_count[g.stitch[i].row];
    }
  for (int r = 0; r + 1 < n; ++r)
    EXPECT_LT(y_sum[r] / y_count[r], y_sum[r + 1] / y_count[r + 1]) << "row " << r;
  for (const char* size : {"course_extent_cm", "wale_extent_cm"}) {
    const double a = s.report.summary.at(size).get<double>(),
                 b = u.report.summary.at(size).get<double>();
    EXPECT_NEAR(a / b, 1.0, 0.03) << size << ": striped " << a << ", one yarn " << b;
  }
  std::filesystem::remove_all(dir);
}

TEST(Knitout, AProgramIsRelaxedAtItsOwnSize) {
  KnitOptions k;
  k.rows = 4;
  k.cols = 4;
  EXPECT_NO_THROW(check_knitout_size(YARNS + "swatch4x4garter.k", k));
  k.cols = 5;
  try {
    check_knitout_size(YARNS + "swatch4x4garter.k", k);
    FAIL() << "a 4 × 5 relaxation of a 4 × 4 program was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the program knits 4 rows × 4 columns flat"),
              std::string::npos)
        << e.what();
  }
  // and the relaxation knits the program's chart: garter's rows alternate
  RelaxKnitOptions o;
  o.knit.rows = 4;
  o.knit.cols = 4;
  o.run.max_time = 5 * o.params.solver.time_step;
  o.run.progress = false;
  const RelaxResult r = relax_knit(YARNS + "swatch4x4garter.k", o);
  EXPECT_EQ(r.model.knit->pattern, YARNS + "swatch4x4garter.k");
  EXPECT_EQ(r.report.status, StepStatus::OK);
}

// A knitout program is known by its header, whatever its name: a chart reader would call
// its first ';' an unknown stitch
TEST(Knitout, AProgramIsKnownByItsHeaderWhateverItsName) {
  std::ifstream in(YARNS + "swatch4x4garter.k");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string dir = ::testing::TempDir();
  for (const std::string name : {"garter.txt", "garter.knitout", "garter"}) {
    std::ofstream(dir + "/" + name) << text;
    EXPECT_TRUE(is_knitout_path(dir + "/" + name)) << name;
    EXPECT_EQ(load_pattern(dir + "/" + name).rows,
              load_knitout(YARNS + "swatch4x4garter.k").pattern.rows)
        << name;
  }
  std::ofstream(dir + "/bom.txt") << "\xEF\xBB\xBF" << text;
  EXPECT_TRUE(is_knitout_path(dir + "/bom.txt"));
  // a chart, a missing file, a directory and a device are not programs (and not opened)
  std::ofstream(dir + "/chart.txt") << "kp\npk\n";
  EXPECT_FALSE(is_knitout_path(dir + "/chart.txt"));
  EXPECT_EQ(load_pattern(dir + "/chart.txt").num_cols(), 2);
  EXPECT_FALSE(is_knitout_path(dir + "/no_such_file"));
  EXPECT_FALSE(is_knitout_path(dir));
  EXPECT_FALSE(is_knitout_path("/dev/zero"));
  // and the size check of a relaxation reads it as a program too
  KnitOptions k;
  k.rows = 4;
  k.cols = 5;
  EXPECT_THROW(check_knitout_size(dir + "/garter.txt", k), std::invalid_argument);
}

}  // namespace
}  // namespace knit
