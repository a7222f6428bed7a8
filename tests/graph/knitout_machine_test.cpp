// One tiny knitout program per instruction, run on the machine model; each graph is
// checked against what the instruction means on a V-bed machine: which loops a new loop
// is pulled through and in which order, its face and kind, crossings made by racking,
// the yarn's sequence, and programs the machine would refuse (with their line).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "knit/graph/knitout_machine.hpp"

namespace knit::graph {
namespace {

// a program: the header, then `body`
std::string prog(const std::string& body) {
  return ";!knitout-2\n;;Machine: SWGXYZ\n;;Gauge: 15\n;;Carriers: 1 2 3\n" + body;
}

KnitoutResult run(const std::string& body) {
  return run_knitout(prog(body), "t.k");
}

std::string refusal(const std::string& body) {
  try {
    run_knitout(prog(body), "t.k");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(accepted)";
}

// the header takes 4 lines: the body's line k is the program's line 4 + k
constexpr int H = 4;

std::vector<LoopId> parents_of(const KnitGraph& g, LoopId id) {
  const auto p = g.parents(id);
  return {p.begin(), p.end()};
}

TEST(KnitoutMachine, KnitPullsANewLoopThroughTheLoopOnItsNeedle) {
  const KnitoutResult r =
      run("inhook 3\n"       // 1
          "tuck - f1 3\n"    // 2: cast on: a new loop on an empty needle
          "releasehook 3\n"  // 3
          "knit + f1 3\n"    // 4: through the cast-on loop
          "knit - f1 3\n"    // 5
          "outhook 3\n");    // 6
  const KnitGraph& g = r.graph;
  ASSERT_EQ(g.num_loops(), 3u);
  const Loop& cast = g.loop(0);
  EXPECT_EQ(cast.kind, LoopKind::NEW);
  EXPECT_EQ(cast.line, H + 2);
  EXPECT_TRUE(g.parents(0).empty());
  EXPECT_EQ(g.loop(1).kind, LoopKind::KNIT);
  EXPECT_EQ(parents_of(g, 1), std::vector<LoopId>{0});
  EXPECT_EQ(parents_of(g, 2), std::vector<LoopId>{1});
  EXPECT_EQ(g.loop(1).face,
            Face::KNIT);  // pulled towards the front bed: a knit seen from the front
  EXPECT_EQ(g.loop(1).bed, Bed::FRONT);
  EXPECT_EQ(g.loop(1).needle, 1);
  // the yarn turns at every pass: courses 0, 1, 2
  EXPECT_EQ(g.loop(0).course, 0);
  EXPECT_EQ(g.loop(1).course, 1);
  EXPECT_EQ(g.loop(2).course, 2);
  EXPECT_EQ(g.loop(1).end, LoopEnd::CONSUMED);
  EXPECT_EQ(g.loop(1).end_line, H + 5);
  ASSERT_EQ(g.children(1).size(), 1u);
  EXPECT_EQ(g.children(1)[0], 2u);
  // one yarn, in at line 1, out at line 6, through its three loops in order
  ASSERT_EQ(g.yarns().size(), 1u);
  const Yarn& y = g.yarns()[0];
  EXPECT_EQ(y.carrier, "3");
  EXPECT_EQ(y.in_line, H + 1);
  EXPECT_EQ(y.out_line, H + 6);
  EXPECT_TRUE(y.hook);
  ASSERT_EQ(y.steps.size(), 3u);
  for (LoopId k = 0; k < 3; ++k) EXPECT_EQ(y.steps[k].loop, k);
  // the last loop is still on its needle: free at the top edge
  const GraphCheck c = g.check();
  EXPECT_TRUE(c.ok()) << c.problems[0];
  EXPECT_EQ(c.free_live, std::vector<LoopId>{2});
  EXPECT_TRUE(c.ladders.empty());
  EXPECT_EQ(r.headers.at("Machine"), "SWGXYZ");
  EXPECT_EQ(r.headers.at("Gauge"), "15");
  EXPECT_EQ(r.version, 2);
}

TEST(KnitoutMachine, BackBedLoopsShowTheirPurlSideToTheFront) {
  const KnitoutResult r = run("in 1\nknit + b1 1\nknit - b1 1\nknit + f1 1\n");
  EXPECT_EQ(r.graph.loop(0).kind, LoopKind::NEW);  // a knit on an empty needle
  EXPECT_EQ(r.graph.loop(1).face, Face::PURL);
  EXPECT_EQ(r.graph.loop(1).bed, Bed::BACK);
  EXPECT_EQ(r.graph.loop(2).face, Face::KNIT);
  EXPECT_TRUE(r.graph.parents(2).empty());  // f1 held nothing
  // carrier 1 was never taken out: noted, its yarn open at the end
  EXPECT_EQ(r.graph.yarns()[0].out_line, 0);
  EXPECT_FALSE(r.notes.empty());
}

TEST(KnitoutMachine, PurlOpcodeIsAKnitPulledTheOtherWayWithANote) {
  const KnitoutResult r = run("in 1\ntuck + f1 1\npurl - f1 1\npurl + b1 1\n");
  EXPECT_EQ(r.graph.loop(1).kind, LoopKind::KNIT);
  EXPECT_EQ(r.graph.loop(1).face, Face::PURL);
  EXPECT_EQ(parents_of(r.graph, 1), std::vector<LoopId>{0});
  EXPECT_EQ(r.graph.loop(2).face, Face::KNIT);  // a purl on the back bed shows its knit side
  bool noted = false;
  for (const KnitoutNote& n : r.notes)
    if (n.text.find("purl") != std::string::npos) {
      noted = true;
      EXPECT_EQ(n.line, H + 3);
      EXPECT_EQ(n.count, 2);
    }
  EXPECT_TRUE(noted);
}

TEST(KnitoutMachine, TuckLaysALoopBesideTheLoopsThereAndTheNextKnitTakesBoth) {
  const KnitoutResult r =
      run("in 1\n"
          "tuck + f1 1\n"  // 0: new
          "knit - f1 1\n"  // 1: through 0
          "tuck + f1 1\n"  // 2: a tuck on top of 1
          "knit - f1 1\n"  // 3: through 1 and 2, bottom first
          "out 1\n");
  const KnitGraph& g = r.graph;
  EXPECT_EQ(g.loop(2).kind, LoopKind::TUCK);
  EXPECT_TRUE(g.parents(2).empty());
  EXPECT_EQ(parents_of(g, 3), (std::vector<LoopId>{1, 2}));
  EXPECT_TRUE(g.check().ok());
}

TEST(KnitoutMachine, AStackedDecreaseKeepsTheMovedLoopOnTop) {
  // f1's loop moves to f2 through the back bed (at racking 1, b1 faces f2); f2's own loop
  // stays at the bottom; the knit on f2 is pulled through both, the moved one last (on top)
  const KnitoutResult r =
      run("in 1\n"
          "knit + f1 1\n"  // 0
          "knit + f2 1\n"  // 1
          "xfer f1 b1\n"
          "rack 1\n"
          "xfer b1 f2\n"
          "rack 0\n"
          "knit - f2 1\n"  // 2
          "knit - f1 1\n"  // 3: f1 is empty: a new loop (the decrease left it bare)
          "out 1\n");
  const KnitGraph& g = r.graph;
  EXPECT_EQ(parents_of(g, 2), (std::vector<LoopId>{1, 0}));
  EXPECT_EQ(g.loop(2).kind, LoopKind::KNIT);
  EXPECT_EQ(g.loop(3).kind, LoopKind::NEW);
  EXPECT_TRUE(g.crossings().empty());  // nothing was on the front bed for b1 to pass
  EXPECT_TRUE(g.check().ok());
  EXPECT_EQ(g.check().free_live, (std::vector<LoopId>{2, 3}));
}

TEST(KnitoutMachine, SplitPullsALoopThroughAndMovesTheOldOnesAcross) {
  const KnitoutResult r =
      run("in 1\n"
          "knit + f1 1\n"      // 0
          "split + f1 b1 1\n"  // 1: through 0; 0 moves to b1
          "knit - b1 1\n"      // 2: through 0 again, on the back bed
          "split - f1 b1\n"    // no carrier: a transfer of 1 to b1
          "knit + b1 1\n"      // 3: through 2 then 1 (1 arrived on top)
          "out 1\n");
  const KnitGraph& g = r.graph;
  EXPECT_EQ(g.loop(1).kind, LoopKind::SPLIT);
  EXPECT_EQ(parents_of(g, 1), std::vector<LoopId>{0});
  EXPECT_EQ(parents_of(g, 2), std::vector<LoopId>{0});
  EXPECT_EQ(g.loop(2).face, Face::PURL);
  EXPECT_EQ(g.children(0).size(), 2u);  // split through, then knit through
  EXPECT_EQ(parents_of(g, 3), (std::vector<LoopId>{2, 1}));
  EXPECT_TRUE(g.check().ok());
}

TEST(KnitoutMachine, DropLeavesALadderNamingItsLine) {
  const KnitoutResult r =
      run("in 1\n"
          "knit + f1 1\n"  // 0
          "knit + f2 1\n"  // 1
          "knit - f2 1\n"  // 2 (holds 1)
          "drop f1\n"      // 5: 0 is held by no loop: a ladder
          "knit + f2\n"    // 6: a knit without yarn drops too
          "drop f3\n"      // an empty needle: nothing
          "out 1\n");
  const GraphCheck c = r.graph.check();
  EXPECT_TRUE(c.ok());
  EXPECT_EQ(c.ladders, (std::vector<LoopId>{0, 2}));
  EXPECT_EQ(r.graph.loop(0).end, LoopEnd::DROPPED);
  EXPECT_EQ(r.graph.loop(0).end_line, H + 5);
  EXPECT_EQ(r.graph.loop(2).end_line, H + 6);
  EXPECT_EQ(r.graph.loop(1).end, LoopEnd::CONSUMED);
  EXPECT_TRUE(c.free_live.empty());
}

TEST(KnitoutMachine, AmissAndTuckWithoutYarnMakeNothing) {
  const KnitoutResult r = run("in 1\nknit + f1 1\namiss f1\ntuck + f1\nknit - f1 1\nout 1\n");
  ASSERT_EQ(r.graph.num_loops(), 2u);
  EXPECT_EQ(parents_of(r.graph, 1), std::vector<LoopId>{0});
}

TEST(KnitoutMachine, MissMovesTheYarnPastANeedle) {
  const KnitoutResult r = run("in 2\nknit + f1 2\nmiss + f2 2\nmiss + f3 2\nknit - f3 2\nout 2\n");
  const Yarn& y = r.graph.yarns()[0];
  ASSERT_EQ(y.steps.size(), 4u);
  EXPECT_EQ(y.steps[1].kind, YarnStep::MISS);
  EXPECT_EQ(y.steps[1].needle, 2);
  EXPECT_EQ(y.steps[2].needle, 3);
  EXPECT_EQ(y.steps[3].kind, YarnStep::LOOP);
  EXPECT_EQ(r.graph.num_loops(), 2u);
  // the yarn turned after its miss to the right: the loop at f3 is on the next course
  EXPECT_EQ(r.graph.loop(1).course, 1);
}

TEST(KnitoutMachine, TwoCarriersMakeTwoYarnsAndPlatingTwoLoops) {
  const KnitoutResult r =
      run("in 1\nin 2\n"
          "knit + f1 1\n"    // 0 yarn 0
          "knit + f1 2\n"    // 1 yarn 1, through 0
          "knit - f1 1 2\n"  // 2, 3: both yarns pulled through 1
          "out 1\n"
          "in 1\n"         // a new piece of yarn on carrier 1
          "knit + f1 1\n"  // 4 through 2 and 3
          "out 1\nout 2\n");
  const KnitGraph& g = r.graph;
  ASSERT_EQ(g.yarns().size(), 3u);
  EXPECT_EQ(g.loop(0).yarn, 0);
  EXPECT_EQ(g.loop(1).yarn, 1);
  EXPECT_EQ(g.loop(2).yarn, 0);
  EXPECT_EQ(g.loop(3).yarn, 1);
  EXPECT_EQ(parents_of(g, 2), std::vector<LoopId>{1});
  EXPECT_EQ(parents_of(g, 3), std::vector<LoopId>{1});
  EXPECT_EQ(parents_of(g, 4), (std::vector<LoopId>{2, 3}));
  EXPECT_EQ(g.loop(4).yarn, 2);
  EXPECT_EQ(g.yarns()[0].out_line, H + 6);
  EXPECT_EQ(g.yarns()[2].in_line, H + 7);
  EXPECT_EQ(g.yarns()[2].carrier, "1");
  EXPECT_EQ(g.yarns()[1].steps.size(), 2u);
  EXPECT_TRUE(g.check().ok());
}

// a 1×1 cable (a twist): A on f1 and B on f2 go to the back bed, A comes to f2 first, then
// B to f1. While A is on the front bed and B still on the back, the racking carries B past
// A: A passes in front.
TEST(KnitoutMachine, ACableCrossesItsLoopsWithTheFirstMovedInFront) {
  const std::string twist =
      "in 1\n"
      "knit + f1 1\n"  // 0: A
      "knit + f2 1\n"  // 1: B
      "xfer f1 b1\nxfer f2 b2\n"
      "rack 1\nxfer b1 f2\n"  // line 7: A to f2
      "rack -1\n"             // line 8: B (b2) moves from facing f3 to facing f1, past A
      "xfer b2 f1\nrack 0\n"
      "knit - f2 1\nknit - f1 1\n"  // 2 through A on f2, 3 through B on f1
      "out 1\n";
  const KnitoutResult r = run(twist);
  const auto crossings = r.graph.crossings();
  ASSERT_EQ(crossings.size(), 1u);
  EXPECT_EQ(crossings[0].front, 0u);
  EXPECT_EQ(crossings[0].back, 1u);
  EXPECT_EQ(crossings[0].line, H + 8);
  EXPECT_EQ(parents_of(r.graph, 2), std::vector<LoopId>{0});
  EXPECT_EQ(parents_of(r.graph, 3), std::vector<LoopId>{1});
  EXPECT_EQ(r.graph.loop(0).needle, 1);  // where it was made
}

TEST(KnitoutMachine, RackingPastALoopAndBackLeavesNoCrossing) {
  const KnitoutResult r =
      run("in 1\nknit + f1 1\nknit + f2 1\n"
          "xfer f1 b1\n"
          "rack 2\n"  // b1 faces f3: carried past f2's loop
          "rack 0\n"  // and back
          "xfer b1 f1\nout 1\n");
  EXPECT_TRUE(r.graph.crossings().empty());
  // carried past and left there: the crossing stays
  const KnitoutResult s = run("in 1\nknit + f1 1\nknit + f2 1\nxfer f1 b1\nrack 2\nout 1\n");
  ASSERT_EQ(s.graph.crossings().size(), 1u);
  EXPECT_EQ(s.graph.crossings()[0].front, 1u);
  EXPECT_EQ(s.graph.crossings()[0].back, 0u);
  // in two steps (beside it in between): one crossing
  const KnitoutResult t =
      run("in 1\nknit + f1 1\nknit + f2 1\nxfer f1 b1\nrack 1\nrack 2\nout 1\n");
  EXPECT_EQ(t.graph.crossings().size(), 1u);
  // to face it and back: none
  const KnitoutResult u =
      run("in 1\nknit + f1 1\nknit + f2 1\nxfer f1 b1\nrack 1\nrack 0\nout 1\n");
  EXPECT_TRUE(u.graph.crossings().empty());
  // carried past a loop, then back beside it and stacked onto its needle (a decrease by a
  // roundabout racking, as lace programs write them): side by side, they do not cross
  const KnitoutResult v =
      run("in 1\nknit + f1 1\nknit + f2 1\nxfer f1 b1\nxfer f2 b2\nrack 1\nxfer b1 f2\n"
          "rack -1\nrack 0\nxfer b2 f2\nknit - f2 1\nout 1\n");
  EXPECT_TRUE(v.graph.crossings().empty());
  EXPECT_EQ(parents_of(v.graph, 2), (std::vector<LoopId>{0, 1}));
}

TEST(KnitoutMachine, QuarterPitchRackingKnitsBothBedsButTransfersNothing) {
  const KnitoutResult r = run("in 1\nrack +0.25\nknit + f1 1\nknit + b1 1\nrack 0\nout 1\n");
  EXPECT_EQ(r.graph.num_loops(), 2u);
  EXPECT_TRUE(r.graph.crossings().empty());  // b1 moved a quarter needle, past nothing
  const std::string why = refusal("in 1\nknit + f1 1\nrack 0.25\nxfer f1 b1\n");
  EXPECT_NE(why.find("t.k:8:"), std::string::npos) << why;
  EXPECT_NE(why.find("'xfer f1 b1'"), std::string::npos) << why;
  EXPECT_NE(why.find("racking 0.25"), std::string::npos) << why;
  EXPECT_EQ(run("in 1\nrack -0.75\nout 1\n").final_racking, -0.75);
}

TEST(KnitoutMachine, StitchSettingsNameTheLoopLengthInForce) {
  const KnitoutResult r =
      run("in 1\nx-stitch-number 70\nknit + f1 1\nstitch 5 -7.5\nknit - f1 1\nout 1\n");
  const KnitGraph& g = r.graph;
  ASSERT_EQ(g.stitch_settings().size(), 2u);
  EXPECT_EQ(g.stitch_settings()[0].value, 70);
  EXPECT_EQ(g.stitch_settings()[1].value2, -7.5);
  EXPECT_EQ(g.loop(0).stitch_setting, 0);
  EXPECT_EQ(g.loop(1).stitch_setting, 1);
}

TEST(KnitoutMachine, ExtensionsAndPauseAreAcceptedWithANote) {
  const KnitoutResult r =
      run("in 1\nx-presser-mode on\nknit + f1 1\nx-presser-mode off\npause\nx-speed-number 300\n"
          "out 1\n");
  EXPECT_EQ(r.graph.num_loops(), 1u);
  int presser = 0, speed = 0;
  for (const KnitoutNote& n : r.notes) {
    if (n.text.find("x-presser-mode") != std::string::npos) presser = n.count;
    if (n.text.find("x-speed-number") != std::string::npos) speed = n.count;
  }
  EXPECT_EQ(presser, 2);
  EXPECT_EQ(speed, 1);
}

TEST(KnitoutMachine, SlidersHoldLoopsDuringTransfers) {
  const KnitoutResult r = run("in 1\nknit + f1 1\nxfer f1 bs1\nxfer bs1 f1\nknit - f1 1\nout 1\n");
  EXPECT_EQ(parents_of(r.graph, 1), std::vector<LoopId>{0});
  EXPECT_NE(refusal("in 1\nknit + fs1 1\n").find("sliders"), std::string::npos);
}

TEST(KnitoutMachine, RefusesWhatTheMachineWouldRefuseNamingTheLine) {
  struct Case {
    std::string body, line, expected;
  };
  auto tucks = [](int n) {
    std::string t;
    for (int k = 0; k < n; ++k) t += "tuck + f1 1\n";
    return t;
  };
  const std::vector<Case> cases = {
      {"knit + f1 1\n", ":5:", "carrier 1 is not in"},
      {"in 1\nout 1\nknit + f1 1\n", ":7:", "carrier 1 is not in"},
      {"in 1\nin 1\n", ":6:", "already in"},
      {"in 4\n", ":5:", "not one of the machine's carriers"},
      {"in 1\nknit + f1 1 1\n", ":6:", "named twice"},
      {"releasehook 1\n", ":5:", "holds no carrier"},
      {"inhook 1\nreleasehook 2\n", ":6:", "holds carrier(s) 1"},
      {"inhook 1\ninhook 2\n", ":6:", "releasehook"},
      {"in 1\nknit f1 1\n", ":6:", "expected a direction"},
      {"in 1\nknit + x1 1\n", ":6:", "expected a needle such as f12"},
      {"in 1\nknit + f1.5 1\n", ":6:", "expected a needle"},
      {"in 1\nknit + f20000 1\n", ":6:", "beyond the needles"},
      {"in 1\nxfer f1 f2\n", ":6:", "opposite beds"},
      {"in 1\nrack 1\nxfer f1 b1\n", ":7:", "expected 'rack 0'"},
      {"in 1\nxfer f3 b1\n", ":6:", "f3 faces b3, not b1: expected 'rack 2'"},
      {"rack x\n", ":5:", "expected a racking"},
      {"rack 100\n", ":5:", "beyond the"},
      {"frobnicate f1\n", ":5:", "unknown instruction 'frobnicate'"},
      {"in 1\ndrop\n", ":6:", "expected 'drop N'"},
      {"stitch 5\n", ":5:", "expected 'stitch L T'"},
      {"in 1\nsplit + f1 1\n", ":6:", "expected a needle"},
      {"in 1\nmiss + f1\n", ":6:", "expected 'miss D N CS'"},
      {"in 1\n" + tucks(33), ":38:", "would hold 33 loops"},
      {"in 1\nrack 33\n", ":6:", "beyond the"},
  };
  for (const Case& c : cases) {
    const std::string why = refusal(c.body);
    EXPECT_NE(why.find("t.k" + c.line), std::string::npos) << c.body << " -> " << why;
    EXPECT_NE(why.find(c.expected), std::string::npos) << c.body << " -> " << why;
  }
  // the instruction is quoted as written
  EXPECT_NE(refusal("in 1\n  knit  + x1 1 ; a comment\n").find("'knit  + x1 1'"),
            std::string::npos);
  // the first line
  try {
    run_knitout("knit + f1 1\n", "t.k");
    ADD_FAILURE() << "accepted a program without the knitout header";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("t.k:1:"), std::string::npos) << e.what();
  }
  EXPECT_THROW(run_knitout("", "t.k"), std::invalid_argument);
}

TEST(KnitoutMachine, TheBedsWidthBoundsTheNeedlesUsed) {
  const std::string head = ";!knitout-2\n;;Width: 10\n;;Carriers: 1\nin 1\n";
  EXPECT_NO_THROW(run_knitout(head + "knit + f-3 1\nknit + b6 1\n", "w.k"));  // 10 needles
  try {
    run_knitout(head + "knit + f-3 1\nknit + b7 1\n", "w.k");
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find("w.k:6: 'knit + b7 1'"), std::string::npos) << why;
    EXPECT_NE(why.find("off the bed"), std::string::npos) << why;
  }
  EXPECT_THROW(run_knitout(";!knitout-2\n;;Width: wide\n", "w.k"), std::invalid_argument);
}

TEST(KnitoutMachine, WithoutACarriersHeaderAnyNameIsACarrier) {
  const KnitoutResult r = run_knitout(";!knitout-2\nin A\nknit + f1 A\nout A\n", "t.k");
  EXPECT_EQ(r.graph.yarns()[0].carrier, "A");
}

TEST(KnitoutMachine, PassesChangeWithDirectionCarrierOrATransfer) {
  const KnitoutResult r =
      run("in 1\nin 2\nknit + f1 1\nknit + f2 1\n"  // pass 0
          "knit - f2 1\n"                           // 1
          "knit - f1 2\n"                           // 2: another carrier
          "xfer f2 b2\nknit - f0 2\n"               // 3: after a transfer
          "out 1\nout 2\n");
  std::vector<int> passes;
  for (const Loop& l : r.graph.loops()) passes.push_back(l.pass);
  EXPECT_EQ(passes, (std::vector<int>{0, 0, 1, 2, 3}));
  EXPECT_EQ(r.graph.passes(), 4);
}

TEST(KnitoutMachine, CrlfLinesAndABomAreRead) {
  const KnitoutResult r =
      run_knitout("\xEF\xBB\xBF;!knitout-2\r\nin 1\r\nknit + f1 1\r\nout 1\r\n", "t.k");
  EXPECT_EQ(r.graph.num_loops(), 1u);
  EXPECT_EQ(r.graph.loop(0).line, 3);
}

TEST(KnitoutMachine, AFileOverTheSizeLimitIsRefusedBeforeReading) {
  const std::string path = ::testing::TempDir() + "knit_big.k";
  {
    std::ofstream out(path, std::ios::binary);
    out << ";!knitout-2\n";
  }
  std::filesystem::resize_file(path, MAX_KNITOUT_BYTES + 1);  // sparse: nothing written
  try {
    load_knitout_graph(path);
    ADD_FAILURE() << "a file over the limit was read";
  } catch (const std::invalid_argument& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find(path), std::string::npos) << why;
    EXPECT_NE(why.find("64"), std::string::npos) << why;  // the limit, 64 MB
  }
  std::filesystem::remove(path);
  EXPECT_THROW(load_knitout_graph(path), std::invalid_argument);  // not there
}

}  // namespace
}  // namespace knit::graph
