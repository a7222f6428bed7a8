// One tiny chart per hand-knitting stitch, built into the knit graph; each graph is
// checked against what the stitch means: the loops a new loop is pulled through and
// their order (the last lies on top, in front as seen from the right side), its face as
// seen from the front, its kind, crossings and which loop passes in front, the yarn's
// sequence with the floats of slips and stranded colourwork, bind-offs leaving no live
// loop, short rows making courses of fewer loops; charts that cannot be knitted are
// refused naming their line and cell; k/p charts give the faces of the built-in patterns;
// and the sample charts in tests/data/charts.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "knit/graph/chart.hpp"
#include "knit/pattern/pattern.hpp"

namespace knit::graph {
namespace {

const std::string DATA = std::string(KNIT_TEST_DATA);

ChartResult chart(const std::string& text) {
  return read_chart_graph(text, "t.chart");
}

std::string refusal(const std::string& text) {
  try {
    read_chart_graph(text, "t.chart");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(accepted)";
}

std::vector<LoopId> parents_of(const KnitGraph& g, LoopId id) {
  const auto p = g.parents(id);
  return {p.begin(), p.end()};
}

// the loops chart row `row` made, left to right (by needle, then in the order made)
std::vector<LoopId> row_loops(const ChartResult& c, int row) {
  std::vector<LoopId> out;
  for (const Loop& l : c.graph.loops())
    if (l.line == row && c.symbol_of(l.id) != "cast-on") out.push_back(l.id);
  std::stable_sort(out.begin(), out.end(), [&](LoopId a, LoopId b) {
    return c.graph.loop(a).needle < c.graph.loop(b).needle;
  });
  return out;
}

// the one loop row `row` made at `needle` with a parent (a knit), or else any
LoopId at(const ChartResult& c, int row, int needle) {
  LoopId found = NO_LOOP;
  for (const Loop& l : c.graph.loops())
    if (l.line == row && l.needle == needle && c.symbol_of(l.id) != "cast-on") {
      if (found == NO_LOOP || l.kind == LoopKind::KNIT) found = l.id;
    }
  EXPECT_NE(found, NO_LOOP) << "no loop at row " << row << " needle " << needle;
  return found;
}

// the graph is sound, and the only loops no loop holds are the stitches left on the
// needle (the live top, tucks and wraps included) and the fastened-off ends of bind-offs
void expect_clean(const ChartResult& c) {
  const GraphCheck k = c.graph.check();
  EXPECT_TRUE(k.ok()) << (k.problems.empty() ? "" : k.problems.front());
  EXPECT_TRUE(k.ladders.empty());
  std::set<LoopId> expected(c.fastened_off.begin(), c.fastened_off.end());
  for (const auto& stack : c.live)
    for (LoopId l : stack) expected.insert(l);
  const std::set<LoopId> free(k.free_live.begin(), k.free_live.end());
  EXPECT_EQ(free, expected);
  // every live stitch's loops are live, every other loop was consumed or fastened off
  for (const Loop& l : c.graph.loops()) {
    const LoopEnd want = expected.count(l.id) ? LoopEnd::LIVE : LoopEnd::CONSUMED;
    EXPECT_EQ(l.end, want) << "loop " << l.id;
  }
  EXPECT_EQ(c.loop_symbol.size(), c.graph.num_loops());
}

// the needles a yarn's steps visit in one row, in order, as "L3" (a loop) or "M3" (a miss)
std::vector<std::string> steps_in_row(const ChartResult& c, int yarn, int row) {
  std::vector<std::string> out;
  for (const YarnStep& s : c.graph.yarns()[static_cast<std::size_t>(yarn)].steps)
    if (s.line == row)
      out.push_back((s.kind == YarnStep::LOOP ? "L" : "M") + std::to_string(s.needle));
  return out;
}

// ---- knit and purl, faces, rows ----

TEST(Chart, KnitRowsPullEachLoopThroughTheOneBelow) {
  const ChartResult c = chart("k k k\nk k k\n");
  expect_clean(c);
  ASSERT_EQ(c.cast_on.size(), 3u);
  EXPECT_EQ(c.rows, 2);
  EXPECT_EQ(c.stitches, (std::vector<int>{3, 3, 3}));
  for (int r = 1; r <= 2; ++r)
    for (int n = 1; n <= 3; ++n) {
      const LoopId l = at(c, r, n);
      EXPECT_EQ(c.graph.loop(l).kind, LoopKind::KNIT);
      // a k cell shows a knit from the right side on either row
      EXPECT_EQ(c.graph.loop(l).face, Face::KNIT);
      const LoopId below = r == 1 ? c.cast_on[static_cast<std::size_t>(n - 1)] : at(c, r - 1, n);
      EXPECT_EQ(parents_of(c.graph, l), std::vector<LoopId>{below});
    }
  // right-side row 1 is worked right to left, wrong-side row 2 left to right
  EXPECT_EQ(steps_in_row(c, 0, 1), (std::vector<std::string>{"L3", "L2", "L1"}));
  EXPECT_EQ(steps_in_row(c, 0, 2), (std::vector<std::string>{"L1", "L2", "L3"}));
  EXPECT_EQ(c.graph.loop(at(c, 1, 1)).direction, Direction::MINUS);
  EXPECT_EQ(c.graph.loop(at(c, 2, 1)).direction, Direction::PLUS);
  EXPECT_EQ(c.graph.yarns().size(), 1u);
  EXPECT_EQ(c.graph.yarns()[0].carrier, "A");
  EXPECT_EQ(c.live.size(), 3u);
}

TEST(Chart, PurlCellsShowPurlFromTheFront) {
  const ChartResult c = chart("p p\np p\n");
  expect_clean(c);
  for (int r = 1; r <= 2; ++r)
    for (int n = 1; n <= 2; ++n) EXPECT_EQ(c.graph.loop(at(c, r, n)).face, Face::PURL);
}

TEST(Chart, WorkedCellsAPurlOnAWrongSideRowShowsAsAKnit) {
  // cells: worked names what the knitter does: purling the wrong side makes stockinette,
  // knitting every row makes garter
  const ChartResult st = chart("cells: worked\np p\nk k\n");
  expect_clean(st);
  for (int n = 1; n <= 2; ++n) {
    EXPECT_EQ(st.graph.loop(at(st, 1, n)).face, Face::KNIT);
    EXPECT_EQ(st.graph.loop(at(st, 2, n)).face, Face::KNIT);
  }
  const ChartResult ga = chart("cells: worked\nk k\nk k\n");
  for (int n = 1; n <= 2; ++n) {
    EXPECT_EQ(ga.graph.loop(at(ga, 1, n)).face, Face::KNIT);
    EXPECT_EQ(ga.graph.loop(at(ga, 2, n)).face, Face::PURL);
  }
}

TEST(Chart, WorkedCellsOnAWrongSideRowAreSeenFromTheOtherSide) {
  // row 2 is worked from the wrong side: a slip with the yarn in front (towards the
  // knitter) leaves the float on the wrong side; a knitted c4f shows purl faces from the
  // front, and its held-in-front stitches (the first two worked, on the left as seen from
  // the front) pass behind as seen from the front, going right
  const ChartResult c = chart("cells: worked\nslwyif c4f\nk k k k k\n");
  expect_clean(c);
  ASSERT_EQ(c.floats.size(), 1u);
  EXPECT_EQ(c.floats[0].side, FloatSide::BACK);
  std::set<std::pair<LoopId, LoopId>> got, want;
  for (const Crossing& x : c.graph.crossings()) got.insert({x.front, x.back});
  for (int f : {2, 3})
    for (int b : {4, 5}) want.insert({at(c, 2, f), at(c, 2, b)});
  EXPECT_EQ(got, want);
  EXPECT_EQ(parents_of(c.graph, at(c, 2, 4)), std::vector<LoopId>{at(c, 1, 2)});
  for (int n = 2; n <= 5; ++n) EXPECT_EQ(c.graph.loop(at(c, 2, n)).face, Face::PURL);
}

TEST(Chart, TheDocumentsExamplesRead) {
  for (const char* text : {"k k  k    k k\nk k  k    k k\nk yo k2tog k k\n",
                           "bo bo bo bo\nk k k k\n", "k k . .\nk k bo bo\n"}) {
    SCOPED_TRACE(text);
    expect_clean(chart(text));
  }
}

TEST(Chart, ReadsCommasTabsCarriageReturnsAndAByteOrderMark) {
  const ChartResult c = chart("\xEF\xBB\xBFK,\tP , k\r\nk p k\r\n");
  expect_clean(c);
  EXPECT_EQ(c.columns, 3);
  EXPECT_EQ(c.graph.loop(at(c, 2, 2)).face, Face::PURL);
  EXPECT_EQ(c.row_line, (std::vector<int>{0, 2, 1}));
}

TEST(Chart, InTheRoundEveryRowIsWorkedFromTheRightSide) {
  const ChartResult c = chart("knit: round\nk k k\nk k k\n");
  expect_clean(c);
  EXPECT_TRUE(c.in_the_round);
  EXPECT_EQ(steps_in_row(c, 0, 2), (std::vector<std::string>{"L3", "L2", "L1"}));
  EXPECT_EQ(c.graph.loop(at(c, 2, 1)).direction, Direction::MINUS);
  EXPECT_EQ(c.graph.loop(at(c, 2, 1)).face, Face::KNIT);
}

// the k/p charts of the built-in patterns, written out cell by cell and read back as a
// word per row (the k/p chart reader's format), give the faces the pattern names
TEST(Chart, KnitPurlChartsGiveTheBuiltInPatternsFaces) {
  const std::vector<std::pair<std::string, std::string>> charts = {
      {"stockinette", "k k k k\nk k k k\nk k k k\nk k k k\n"},
      {"reverse_stockinette", "p p p p\np p p p\n"},
      {"garter", "p p p p\nk k k k\np p p p\nk k k k\n"},
      {"rib1x1", "k p k p\nk p k p\nk p k p\n"},
      {"rib2x2", "k k p p\nk k p p\n"},
      {"seed", "p k p k\nk p k p\np k p k\nk p k p\n"},
  };
  for (const auto& [name, text] : charts) {
    SCOPED_TRACE(name);
    const knit::Pattern p = knit::builtin_pattern(name);
    for (const bool as_words : {false, true}) {
      std::string body = text;
      if (as_words) body.erase(std::remove(body.begin(), body.end(), ' '), body.end());
      const ChartResult c = chart(body);
      expect_clean(c);
      for (int r = 1; r <= c.rows; ++r)
        for (int n = 1; n <= c.columns; ++n) {
          const bool knit = p.is_knit((r - 1) % p.num_rows(), (n - 1) % p.num_cols());
          EXPECT_EQ(c.graph.loop(at(c, r, n)).face, knit ? Face::KNIT : Face::PURL)
              << "row " << r << " column " << n;
        }
    }
  }
}

// the built-in patterns, tiled, through the chart path: one loop per stitch, the face
// the pattern names, each loop pulled through the one below it
TEST(Chart, BuiltInPatternsBuildThroughTheChartPath) {
  for (const std::string& name : knit::builtin_pattern_names()) {
    SCOPED_TRACE(name);
    const knit::Pattern p = knit::tile(knit::builtin_pattern(name), 6, 8);
    const ChartResult c = kp_rows_graph(p.rows, name);
    expect_clean(c);
    EXPECT_EQ(c.rows, 6);
    EXPECT_EQ(c.columns, 8);
    EXPECT_EQ(c.graph.num_loops(), 7u * 8u);
    for (int r = 1; r <= 6; ++r)
      for (int n = 1; n <= 8; ++n) {
        const LoopId l = at(c, r, n);
        EXPECT_EQ(c.graph.loop(l).face, p.is_knit(r - 1, n - 1) ? Face::KNIT : Face::PURL);
        const LoopId below = r == 1 ? c.cast_on[static_cast<std::size_t>(n - 1)] : at(c, r - 1, n);
        EXPECT_EQ(parents_of(c.graph, l), std::vector<LoopId>{below});
      }
  }
  EXPECT_THROW(kp_rows_graph({"kp", "kx"}, "p"), std::invalid_argument);
}

// a k/p chart file of the k/p chart reader (knit/pattern) reads here with the faces that
// reader gives it
TEST(Chart, KnitPurlChartFilesReadAsTheKnitPurlReaderReadsThem) {
  for (const std::string& path :
       {DATA + "/patterns/rib_and_seed.chart",
        std::string(KNIT_SOURCE_DIR) + "/fuzz/seeds/chart/case_tabs.chart"}) {
    SCOPED_TRACE(path);
    const knit::Pattern p = knit::load_pattern(path);
    const ChartResult c = load_chart_graph(path);
    expect_clean(c);
    ASSERT_EQ(c.rows, p.num_rows());
    ASSERT_EQ(c.columns, p.num_cols());
    for (int r = 1; r <= c.rows; ++r)
      for (int n = 1; n <= c.columns; ++n)
        EXPECT_EQ(c.graph.loop(at(c, r, n)).face,
                  p.is_knit(r - 1, n - 1) ? Face::KNIT : Face::PURL);
  }
}

TEST(Chart, KnitThroughTheBackLoopIsTwisted) {
  const ChartResult c = chart("k ktbl ptbl\n");
  expect_clean(c);
  EXPECT_EQ(c.twisted, (std::vector<LoopId>{at(c, 1, 3), at(c, 1, 2)}));
  EXPECT_EQ(c.graph.loop(at(c, 1, 2)).face, Face::KNIT);
  EXPECT_EQ(c.graph.loop(at(c, 1, 3)).face, Face::PURL);
  EXPECT_EQ(parents_of(c.graph, at(c, 1, 2)), std::vector<LoopId>{c.cast_on[1]});
}

// ---- decreases: parents bottom first, the last on top ----

TEST(Chart, DecreasesStackTheirParentsInLeaningOrder) {
  struct Case {
    const char* sym;
    int take;
    std::vector<int> order;  // cast-on loops (left to right) bottom first
    Face face;
  };
  const std::vector<Case> cases = {
      {"k2tog", 2, {1, 0}, Face::KNIT},  // right-leaning: the left loop on top
      {"ssk", 2, {0, 1}, Face::KNIT},    // left-leaning: the right loop on top
      {"p2tog", 2, {1, 0}, Face::PURL},    {"ssp", 2, {0, 1}, Face::PURL},
      {"k3tog", 3, {2, 1, 0}, Face::KNIT},  // the leftmost on top
      {"sssk", 3, {0, 1, 2}, Face::KNIT},   // the rightmost on top
      {"sk2p", 3, {1, 0, 2}, Face::KNIT},   // k2tog, the slipped right one passed over it
      {"cdd", 3, {0, 2, 1}, Face::KNIT},    // the middle one on top
      {"p3tog", 3, {2, 1, 0}, Face::PURL},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(k.sym);
    // k DEC k on k + take + k cast-on loops; '.' fills the grid
    std::string row = "k " + std::string(k.sym) + " k";
    for (int i = 1; i < k.take; ++i) row += " .";
    const ChartResult c = chart(row + "\n");
    expect_clean(c);
    ASSERT_EQ(c.cast_on.size(), static_cast<std::size_t>(k.take + 2));
    EXPECT_EQ(c.stitches, (std::vector<int>{k.take + 2, 3}));
    const LoopId d = at(c, 1, 2);
    EXPECT_EQ(c.graph.loop(d).kind, LoopKind::KNIT);
    EXPECT_EQ(c.graph.loop(d).face, k.face);
    std::vector<LoopId> want;
    for (int i : k.order) want.push_back(c.cast_on[static_cast<std::size_t>(1 + i)]);
    EXPECT_EQ(parents_of(c.graph, d), want);
    // the stitches either side are worked into the loops either side
    EXPECT_EQ(parents_of(c.graph, at(c, 1, 1)), std::vector<LoopId>{c.cast_on.front()});
    EXPECT_EQ(parents_of(c.graph, at(c, 1, 3)), std::vector<LoopId>{c.cast_on.back()});
  }
}

TEST(Chart, WorkedDecreaseOnAWrongSideRowKeepsItsParentsOrder) {
  // a k2tog knitted from the wrong side: a purl from the front, the loop on the left (as
  // seen from the front) still on top
  const ChartResult c = chart("cells: worked\nk k2tog k .\nk k k k\n");
  expect_clean(c);
  EXPECT_EQ(c.graph.loop(at(c, 2, 2)).face, Face::PURL);
  EXPECT_EQ(parents_of(c.graph, at(c, 2, 2)), (std::vector<LoopId>{at(c, 1, 3), at(c, 1, 2)}));
}

TEST(Chart, DecreaseOnAWrongSideRowLeansAsItsCellShows) {
  // row 2 is worked left to right; its k2tog still shows the left loop on top
  const ChartResult c = chart("k k2tog k .\nk k k k\n");
  expect_clean(c);
  EXPECT_EQ(c.stitches, (std::vector<int>{4, 4, 3}));
  EXPECT_EQ(parents_of(c.graph, at(c, 2, 2)), (std::vector<LoopId>{at(c, 1, 3), at(c, 1, 2)}));
}

// ---- increases ----

TEST(Chart, YarnOverIsANewLoopWithoutParents) {
  const ChartResult c = chart("k k k\nk yo k\n");
  expect_clean(c);
  EXPECT_EQ(c.stitches, (std::vector<int>{2, 3, 3}));
  const LoopId yo = at(c, 1, 2);
  EXPECT_EQ(c.graph.loop(yo).kind, LoopKind::NEW);
  EXPECT_TRUE(parents_of(c.graph, yo).empty());
  // the yarn runs through it between its neighbours
  EXPECT_EQ(steps_in_row(c, 0, 1), (std::vector<std::string>{"L3", "L2", "L1"}));
  // and the next row knits into it
  EXPECT_EQ(parents_of(c.graph, at(c, 2, 2)), std::vector<LoopId>{yo});
}

TEST(Chart, MakeOneComesFromTheBarBetweenTwoStitches) {
  const ChartResult c = chart("k m1l k m1r k\n");
  expect_clean(c);
  ASSERT_EQ(c.increases.size(), 2u);
  // worked right to left: m1r (column 4) first, between cast-on loops 1 and 2
  EXPECT_EQ(c.increases[0].loop, at(c, 1, 4));
  EXPECT_FALSE(c.increases[0].leans_left);
  EXPECT_EQ(c.increases[0].left, c.cast_on[1]);
  EXPECT_EQ(c.increases[0].right, c.cast_on[2]);
  EXPECT_EQ(c.increases[1].loop, at(c, 1, 2));
  EXPECT_TRUE(c.increases[1].leans_left);
  EXPECT_EQ(c.increases[1].left, c.cast_on[0]);
  EXPECT_EQ(c.increases[1].right, c.cast_on[1]);
  for (const ChartIncrease& i : c.increases) {
    EXPECT_EQ(c.graph.loop(i.loop).kind, LoopKind::NEW);
    EXPECT_TRUE(parents_of(c.graph, i.loop).empty());
  }
}

// ---- slips and tucks ----

TEST(Chart, SlipCarriesTheLoopUpAndTheYarnFloatsPastIt) {
  for (const bool front : {false, true}) {
    SCOPED_TRACE(front ? "wyif" : "wyib");
    const ChartResult c = chart(std::string("k k k\nk ") + (front ? "slwyif" : "sl-wyib") + " k\n");
    expect_clean(c);
    EXPECT_EQ(steps_in_row(c, 0, 1), (std::vector<std::string>{"L3", "M2", "L1"}));
    ASSERT_EQ(c.floats.size(), 1u);
    EXPECT_EQ(c.floats[0].side, front ? FloatSide::FRONT : FloatSide::BACK);
    EXPECT_EQ(c.graph.yarns()[0].steps[c.floats[0].step].kind, YarnStep::MISS);
    // row 1 made no loop at column 2: row 2 knits into the cast-on loop itself
    EXPECT_EQ(row_loops(c, 1).size(), 2u);
    EXPECT_EQ(parents_of(c.graph, at(c, 2, 2)), std::vector<LoopId>{c.cast_on[1]});
  }
}

TEST(Chart, TuckLaysALoopOnTheStitchThatTheNextRowKnitsThroughToo) {
  const ChartResult c = chart("k k k\nk tuck k\n");
  expect_clean(c);
  const LoopId tuck = at(c, 1, 2);
  EXPECT_EQ(c.graph.loop(tuck).kind, LoopKind::TUCK);
  EXPECT_TRUE(parents_of(c.graph, tuck).empty());
  // bottom first: the stitch, then the tuck on it
  EXPECT_EQ(parents_of(c.graph, at(c, 2, 2)), (std::vector<LoopId>{c.cast_on[1], tuck}));
}

// ---- cables and twists ----

// the new loop at each needle of row 1 and the cast-on loop it was pulled through
std::vector<int> sources(const ChartResult& c, int width) {
  std::vector<int> out;
  for (int n = 1; n <= width; ++n) {
    const auto p = parents_of(c.graph, at(c, 1, n));
    EXPECT_EQ(p.size(), 1u);
    out.push_back(
        static_cast<int>(std::find(c.cast_on.begin(), c.cast_on.end(), p[0]) - c.cast_on.begin()));
  }
  return out;
}

// every loop of row 1 at the needles `front` passes in front of every one at `back`, and
// no other pair crosses
void expect_crossings(const ChartResult& c, std::vector<int> front, std::vector<int> back) {
  std::set<std::pair<LoopId, LoopId>> want, got;
  for (int f : front)
    for (int b : back) want.insert({at(c, 1, f), at(c, 1, b)});
  for (const Crossing& x : c.graph.crossings()) got.insert({x.front, x.back});
  EXPECT_EQ(got, want);
}

TEST(Chart, CableFrontCrossesTheRightStitchesToTheLeftInFront) {
  const ChartResult c = chart("c4f\n");
  expect_clean(c);
  // the right two (cast-on 2, 3) go left, in front of the left two
  EXPECT_EQ(sources(c, 4), (std::vector<int>{2, 3, 0, 1}));
  expect_crossings(c, {1, 2}, {3, 4});
  // worked right to left into the needles they go to: the left two first
  EXPECT_EQ(steps_in_row(c, 0, 1), (std::vector<std::string>{"L4", "L3", "L2", "L1"}));
  for (int n = 1; n <= 4; ++n) EXPECT_EQ(c.graph.loop(at(c, 1, n)).face, Face::KNIT);
}

TEST(Chart, CableBackCrossesTheLeftStitchesToTheRightInFront) {
  const ChartResult c = chart("C4B\n");
  expect_clean(c);
  EXPECT_EQ(sources(c, 4), (std::vector<int>{2, 3, 0, 1}));
  expect_crossings(c, {3, 4}, {1, 2});
}

TEST(Chart, CablesOfAnyWidthAndUnevenSplits) {
  {
    const ChartResult c = chart("c6f\n");
    expect_clean(c);
    EXPECT_EQ(sources(c, 6), (std::vector<int>{3, 4, 5, 0, 1, 2}));
    expect_crossings(c, {1, 2, 3}, {4, 5, 6});
  }
  {
    const ChartResult c = chart("c6b\n");
    EXPECT_EQ(sources(c, 6), (std::vector<int>{3, 4, 5, 0, 1, 2}));
    expect_crossings(c, {4, 5, 6}, {1, 2, 3});
  }
  {
    // 2/1 LC: the right two pass left in front of one
    const ChartResult c = chart("2/1lc\n");
    expect_clean(c);
    EXPECT_EQ(sources(c, 3), (std::vector<int>{1, 2, 0}));
    expect_crossings(c, {1, 2}, {3});
  }
  {
    // c3/2b: the left three pass right in front of two
    const ChartResult c = chart("c3/2b\n");
    expect_clean(c);
    EXPECT_EQ(sources(c, 5), (std::vector<int>{3, 4, 0, 1, 2}));
    expect_crossings(c, {3, 4, 5}, {1, 2});
  }
  {
    // wide: 12 stitches, 6 over 6
    const ChartResult c = chart("c12f\n");
    expect_clean(c);
    EXPECT_EQ(c.graph.crossings().size(), 36u);
  }
}

TEST(Chart, TwistsPurlTheStitchesThatPassBehind) {
  {
    const ChartResult c = chart("t2r\n");
    expect_clean(c);
    // right twist: the left stitch goes right in front, knit; the right one purled behind
    EXPECT_EQ(sources(c, 2), (std::vector<int>{1, 0}));
    expect_crossings(c, {2}, {1});
    EXPECT_EQ(c.graph.loop(at(c, 1, 2)).face, Face::KNIT);
    EXPECT_EQ(c.graph.loop(at(c, 1, 1)).face, Face::PURL);
  }
  {
    const ChartResult c = chart("T2L\n");
    EXPECT_EQ(sources(c, 2), (std::vector<int>{1, 0}));
    expect_crossings(c, {1}, {2});
    EXPECT_EQ(c.graph.loop(at(c, 1, 1)).face, Face::KNIT);
    EXPECT_EQ(c.graph.loop(at(c, 1, 2)).face, Face::PURL);
  }
}

TEST(Chart, CableOnAWrongSideRowCrossesAsItsCellShows) {
  const ChartResult c = chart("c4f\nk k k k\n");
  expect_clean(c);
  std::set<std::pair<LoopId, LoopId>> got;
  for (const Crossing& x : c.graph.crossings()) got.insert({x.front, x.back});
  std::set<std::pair<LoopId, LoopId>> want;
  for (int f : {1, 2})
    for (int b : {3, 4}) want.insert({at(c, 2, f), at(c, 2, b)});
  EXPECT_EQ(got, want);
  EXPECT_EQ(parents_of(c.graph, at(c, 2, 1)), std::vector<LoopId>{at(c, 1, 3)});
  // worked left to right
  EXPECT_EQ(steps_in_row(c, 0, 2), (std::vector<std::string>{"L1", "L2", "L3", "L4"}));
}

// ---- bind-off ----

TEST(Chart, BindOffAWholeRowLeavesNoLiveLoop) {
  const ChartResult c = chart("bo bo bo\nk k k\n");
  expect_clean(c);
  EXPECT_TRUE(c.live.empty());
  EXPECT_EQ(c.stitches.back(), 0);
  // worked left to right (row 2): each bound-off loop is pulled through its stitch and
  // the one bound off before it, passed over it (on top)
  const LoopId b1 = at(c, 2, 1), b2 = at(c, 2, 2), b3 = at(c, 2, 3);
  EXPECT_EQ(parents_of(c.graph, b1), std::vector<LoopId>{at(c, 1, 1)});
  EXPECT_EQ(parents_of(c.graph, b2), (std::vector<LoopId>{at(c, 1, 2), b1}));
  EXPECT_EQ(parents_of(c.graph, b3), (std::vector<LoopId>{at(c, 1, 3), b2}));
  EXPECT_EQ(c.fastened_off, std::vector<LoopId>{b3});
  EXPECT_EQ(c.graph.yarns()[0].out_line, 2);
}

TEST(Chart, BindOffPartOfARowShapesTheEdge) {
  // row 1 binds off its right two stitches; the third stitch passes through the last
  const ChartResult c = chart("k k . .\nk k bo bo\n");
  expect_clean(c);
  EXPECT_EQ(c.stitches, (std::vector<int>{4, 2, 2}));
  EXPECT_TRUE(c.fastened_off.empty());
  const LoopId b4 = at(c, 1, 4), b3 = at(c, 1, 3);
  EXPECT_EQ(parents_of(c.graph, b3), (std::vector<LoopId>{c.cast_on[2], b4}));
  EXPECT_EQ(parents_of(c.graph, at(c, 1, 2)), (std::vector<LoopId>{c.cast_on[1], b3}));
}

// ---- short rows ----

TEST(Chart, WrapAndTurnMakesACourseOfFewerLoops) {
  // row 2 turns after four stitches, wrapping the fifth; row 3 works the four back;
  // row 4 knits the wrap together with its stitch
  const ChartResult c = chart(
      "k k k k k k\n"
      "k k k k - -\n"
      "k k k k w&t -\n"
      "k k k k k k\n");
  expect_clean(c);
  EXPECT_EQ(c.short_rows, (std::vector<int>{2, 3}));
  EXPECT_EQ(row_loops(c, 3).size(), 4u);
  EXPECT_EQ(row_loops(c, 2).size(), 5u);  // four stitches and the wrap
  const LoopId wrap = at(c, 2, 5);
  EXPECT_EQ(c.graph.loop(wrap).kind, LoopKind::TUCK);
  EXPECT_EQ(parents_of(c.graph, at(c, 4, 5)), (std::vector<LoopId>{at(c, 1, 5), wrap}));
  EXPECT_EQ(parents_of(c.graph, at(c, 4, 6)), std::vector<LoopId>{at(c, 1, 6)});
  EXPECT_EQ(parents_of(c.graph, at(c, 4, 4)), std::vector<LoopId>{at(c, 3, 4)});
  // row 3 starts where row 2 turned
  EXPECT_EQ(steps_in_row(c, 0, 3), (std::vector<std::string>{"L4", "L3", "L2", "L1"}));
}

TEST(Chart, GermanShortRowsDoubleTheFirstStitchAfterTheTurn) {
  const ChartResult c = chart(
      "k k k k k k\n"
      "k k k ds - -\n"
      "k k k k - -\n"
      "k k k k k k\n");
  expect_clean(c);
  EXPECT_EQ(c.short_rows, (std::vector<int>{2, 3}));
  const LoopId ds = at(c, 3, 4);
  EXPECT_EQ(c.graph.loop(ds).kind, LoopKind::TUCK);
  EXPECT_EQ(parents_of(c.graph, at(c, 4, 4)), (std::vector<LoopId>{at(c, 2, 4), ds}));
  EXPECT_EQ(steps_in_row(c, 0, 3), (std::vector<std::string>{"L4", "L3", "L2", "L1"}));
}

TEST(Chart, ShortRowMustStartWhereTheYarnTurned) {
  const std::string e = refusal(
      "k k k k k k\n"
      "- k k k k k\n"
      "k k k k - -\n"
      "k k k k k k\n");
  EXPECT_NE(e.find("t.chart:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("expected 2 leading '-'"), std::string::npos) << e;
}

// ---- colours ----

TEST(Chart, StripesAreOneYarnPerColour) {
  const ChartResult c = chart("@B k k k\n@A k k k\nk k k\n");
  expect_clean(c);
  ASSERT_EQ(c.graph.yarns().size(), 2u);
  EXPECT_EQ(c.graph.yarns()[0].carrier, "A");
  EXPECT_EQ(c.graph.yarns()[1].carrier, "B");
  EXPECT_EQ(c.graph.yarns()[1].in_line, 3);
  for (int n = 1; n <= 3; ++n) {
    EXPECT_EQ(c.graph.loop(at(c, 2, n)).yarn, 0);
    EXPECT_EQ(c.graph.loop(at(c, 3, n)).yarn, 1);
  }
  EXPECT_TRUE(c.floats.empty());
}

TEST(Chart, StrandedColourworkFloatsTheOtherYarnBehind) {
  const ChartResult c = chart("k@A k@B k@A k@B\n");
  expect_clean(c);
  // right to left: B at 4, A at 3, B at 2, A at 1; the cast-on is B's (the first stitch)
  const int a = c.graph.loop(at(c, 1, 3)).yarn, b = c.graph.loop(at(c, 1, 4)).yarn;
  EXPECT_EQ(c.graph.yarns()[static_cast<std::size_t>(a)].carrier, "A");
  EXPECT_EQ(c.graph.loop(c.cast_on[0]).yarn, b);
  EXPECT_EQ(steps_in_row(c, b, 1), (std::vector<std::string>{"L4", "M3", "L2"}));
  EXPECT_EQ(steps_in_row(c, a, 1), (std::vector<std::string>{"L3", "M2", "L1"}));
  ASSERT_EQ(c.floats.size(), 2u);
  for (const ChartFloat& f : c.floats) EXPECT_EQ(f.side, FloatSide::BACK);
}

TEST(Chart, StrandedRoundsFloatEachYarnBehindTheOther) {
  // two rounds of a two-colour check, worked right to left each round
  const ChartResult c = chart("knit: round\nk@B k@B k@A k@A\nk@A k@A k@B k@B\n");
  expect_clean(c);
  ASSERT_EQ(c.graph.yarns().size(), 2u);
  // round 1: B (columns 3, 4) first, then A (columns 1, 2)
  const int b = c.graph.loop(at(c, 1, 4)).yarn, a = c.graph.loop(at(c, 1, 2)).yarn;
  EXPECT_EQ(c.graph.yarns()[static_cast<std::size_t>(a)].carrier, "A");
  EXPECT_EQ(steps_in_row(c, b, 1), (std::vector<std::string>{"L4", "L3"}));
  EXPECT_EQ(steps_in_row(c, a, 1), (std::vector<std::string>{"L2", "L1"}));
  // round 2: A (columns 3, 4) first, then B (columns 1, 2): neither passes the other's
  // stitches between two of its own
  EXPECT_EQ(steps_in_row(c, a, 2), (std::vector<std::string>{"L4", "L3"}));
  EXPECT_EQ(steps_in_row(c, b, 2), (std::vector<std::string>{"L2", "L1"}));
  EXPECT_TRUE(c.floats.empty());
  // a third colour between two stitches of A floats A behind it
  const ChartResult d = chart("knit: round\nk@A k@C k@A\n");
  const int da = d.graph.loop(at(d, 1, 1)).yarn;
  EXPECT_EQ(steps_in_row(d, da, 1), (std::vector<std::string>{"L3", "M2", "L1"}));
  ASSERT_EQ(d.floats.size(), 1u);
  EXPECT_EQ(d.floats[0].side, FloatSide::BACK);
}

TEST(Chart, IntarsiaBlocksKeepTheirOwnYarns) {
  // two blocks of A worked with two bobbins (A, A2) and a block of B between them
  const ChartResult c = chart(
      "k@A2 k@B k@B k@A\n"
      "k@A2 k@B k@B k@A\n"
      "k@A2 k@B k@B k@A\n");
  expect_clean(c);
  EXPECT_EQ(c.graph.yarns().size(), 3u);
  EXPECT_TRUE(c.floats.empty());
  for (const Yarn& y : c.graph.yarns())
    for (const YarnStep& s : y.steps) {
      EXPECT_EQ(s.kind, YarnStep::LOOP);
      if (s.line == 0) continue;  // the cast-on
      const int n = s.needle;
      const std::string want = n == 1 ? "A2" : n == 4 ? "A" : "B";
      EXPECT_EQ(y.carrier, want) << "needle " << n;
    }
}

// ---- refusals ----

TEST(Chart, RefusesWhatCannotBeKnitNamingLineAndCell) {
  struct Case {
    std::string text;
    std::string where, what;
  };
  const std::vector<Case> cases = {
      {"k k\nk k2togg\n", "t.chart:2:3: cell 2 'k2togg'", "unknown stitch symbol"},
      {"k k k\nk k\n", "t.chart:2:", "covers 2 grid columns, expected 3 like line 1"},
      {"k k k\nk k2tog .\n", "t.chart:1:", "row 2 works 3 stitches, but 2 are live"},
      {"k k k k . .\nc6f\n# a comment\nk k k k . .\n", "t.chart:2:1: cell 1 'c6f'",
       "a cable or twist of 6 stitches, but only 4 are left"},
      {"c3f\n", "t.chart:1:1: cell 1 'c3f'", "expected an even count"},
      {"c40/40f\n", "t.chart:1:1: cell 1 'c40/40f'", "expected 1 to 64 stitches"},
      {"k - k\n", "t.chart:1:3: cell 2 '-'", "between worked stitches"},
      {"m1l k k\n", "t.chart:1:1: cell 1 'm1l'", "needs a stitch on each side"},
      {"k yo bo\n", "t.chart:1:3: cell 2 'yo'", "bound-off stitch is passed over"},
      {"k w&t k\n", "t.chart:1:3: cell 2 'w&t'", "last worked stitch"},
      {"size: 3\nk k\n", "t.chart:1:", "unknown header 'size:'"},
      {"k k\nknit: round\n", "t.chart:2:", "after the first row"},
      {"knit: round\nk - -\n", "t.chart:2:", "in the round"},
      {"k@ k\n", "t.chart:1:1: cell 1 'k@'", "yarn name"},
      {"# nothing\n", "t.chart", "no chart rows"},
      {". .\n", "t.chart:1:", "works no stitch"},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(k.text);
    const std::string e = refusal(k.text);
    EXPECT_NE(e.find(k.where), std::string::npos) << e;
    EXPECT_NE(e.find(k.what), std::string::npos) << e;
  }
}

TEST(Chart, RefusesAFileThatIsNotThere) {
  try {
    load_chart_graph(DATA + "/charts/no-such.chart");
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no-such.chart"), std::string::npos);
  }
}

// ---- the sample charts ----

ChartResult sample(const std::string& name) {
  const ChartResult c = load_chart_graph(DATA + "/charts/" + name);
  expect_clean(c);
  return c;
}

TEST(ChartSamples, CablePanelCrossesItsCablesEveryCrossingRow) {
  const ChartResult c = sample("cable_panel.chart");
  // every row keeps the stitch count; each c6f row crosses 3 x 3 pairs per cable
  for (int s : c.stitches) EXPECT_EQ(s, c.stitches.front());
  std::size_t cable_cells = 0;
  for (const Loop& l : c.graph.loops())
    cable_cells += c.symbol_of(l.id) == "c6f" || c.symbol_of(l.id) == "c6b";
  EXPECT_EQ(c.graph.crossings().size(), cable_cells / 6 * 9);
  EXPECT_GT(cable_cells, 0u);
  // the background stays reverse stockinette beside the cables: purl faces
  for (const Loop& l : c.graph.loops())
    if (c.symbol_of(l.id) == "p") {
      EXPECT_EQ(l.face, Face::PURL);
    }
}

TEST(ChartSamples, LaceRowsBalanceEachYarnOverWithADecrease) {
  const ChartResult c = sample("lace.chart");
  const auto kinds = c.graph.count_by_kind();
  EXPECT_GT(kinds[static_cast<std::size_t>(LoopKind::NEW)], c.cast_on.size());
  for (int s : c.stitches) EXPECT_EQ(s, c.stitches.front());
  // each yarn-over is a new loop with no parents, knit into by the row above
  for (const Loop& l : c.graph.loops())
    if (c.symbol_of(l.id) == "yo") {
      EXPECT_TRUE(c.graph.parents(l.id).empty());
      EXPECT_EQ(c.graph.children(l.id).size(), 1u);
    }
}

TEST(ChartSamples, EdgeDecreasesMakeATrapezoid) {
  const ChartResult c = sample("trapezoid.chart");
  // two stitches fewer every right-side row but the first
  EXPECT_EQ(c.stitches.front(), 16);
  EXPECT_EQ(c.stitches.back(), 8);
  for (int r = 1; r <= c.rows; ++r) {
    const int drop = c.stitches[r - 1] - c.stitches[r];
    EXPECT_EQ(drop, (c.right_side[r] && r > 1) ? 2 : 0) << "row " << r;
  }
  // the decreases lean with the edges: ssk (leaning left) at the right edge, k2tog
  // (leaning right) at the left
  for (const Loop& l : c.graph.loops()) {
    if (c.symbol_of(l.id) == "ssk") {
      EXPECT_GT(l.needle, 8);
    }
    if (c.symbol_of(l.id) == "k2tog") {
      EXPECT_LT(l.needle, 8);
    }
  }
}

TEST(ChartSamples, ShortRowWedgeWorksFewerStitchesEachTurn) {
  const ChartResult c = sample("short_row_wedge.chart");
  ASSERT_GE(c.short_rows.size(), 4u);
  // each short row makes fewer loops than a full row, and fewer than the one before it
  std::size_t full = static_cast<std::size_t>(c.stitches.front());
  std::size_t before = full + 1;
  for (int r : c.short_rows) {
    std::size_t made = 0;
    for (const Loop& l : c.graph.loops()) made += l.line == r && l.kind == LoopKind::KNIT;
    EXPECT_LT(made, full) << "row " << r;
    EXPECT_LE(made, before) << "row " << r;
    before = made;
  }
}

TEST(ChartSamples, StripesAndAnIntarsiaBlockKeepTheirYarns) {
  {
    const ChartResult c = sample("stripes.chart");
    std::set<std::string> names;
    for (const Yarn& y : c.graph.yarns()) names.insert(y.carrier);
    EXPECT_EQ(names, (std::set<std::string>{"A", "B"}));
    // a whole row is one yarn
    for (int r = 1; r <= c.rows; ++r) {
      std::set<int> yarns;
      for (const Loop& l : c.graph.loops())
        if (l.line == r) yarns.insert(l.yarn);
      EXPECT_EQ(yarns.size(), 1u) << "row " << r;
    }
  }
  {
    const ChartResult c = sample("intarsia.chart");
    EXPECT_TRUE(c.floats.empty());
    // the block's yarn B makes loops only inside its columns and rows
    int lo = 1 << 20, hi = -1;
    for (const Loop& l : c.graph.loops())
      if (c.graph.yarns()[static_cast<std::size_t>(l.yarn)].carrier == "B") {
        lo = std::min(lo, l.needle);
        hi = std::max(hi, l.needle);
      }
    EXPECT_GT(lo, 1);
    EXPECT_LT(hi, c.columns);
  }
}

}  // namespace
}  // namespace knit::graph
