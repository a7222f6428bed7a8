#include "knit/pattern/generator.hpp"

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>

#include "knit/spline/basis.hpp"

namespace knit {
namespace {

GeneratedKnit knit(const std::string& name, int rows = 6, int cols = 6, bool round = false) {
  KnitOptions o;
  o.rows = rows;
  o.cols = cols;
  o.in_the_round = round;
  return generate_knit(builtin_pattern(name), o);
}

Eigen::Vector3d at(const GeneratedKnit& g, const YarnPoint& p) {
  return g.control_points.middleCols<4>(p.segment) * bspline_basis(p.t);
}

TEST(Generator, SegmentCountsAndStitchCoordinates) {
  for (bool round : {false, true}) {
    const int rows = 5, cols = 7, k = 8;
    const GeneratedKnit g = knit("rib2x2", rows, cols, round);
    const int turns = round ? 0 : rows - 1;
    // a turn is a half circle joining rows row_height apart, π/2 · 0.742 = 1.17 cm of yarn,
    // laid with segments about as long as a stitch's (4.09 cm / 8 = 0.51 cm): 2 segments
    EXPECT_EQ(g.segments_per_turn, round ? 0 : 2);
    int turn_segments = 0;
    for (const YarnPiece p : g.piece) turn_segments += p == YarnPiece::TURN;
    EXPECT_EQ(turn_segments, turns * g.segments_per_turn);
    ASSERT_GT(g.segments_per_tail, 0);
    // k per stitch, plus each row turn of a flat piece, plus the two tails
    const int expected = rows * cols * k + turns * g.segments_per_turn + 2 * g.segments_per_tail;
    EXPECT_EQ(g.num_segments(), expected) << "round=" << round;
    EXPECT_EQ(g.control_points.cols(), expected + 3);
    ASSERT_EQ(g.piece.size(), g.stitch.size());
    std::map<std::pair<int, int>, int> per_stitch;
    for (int i = 0; i < g.num_segments(); ++i) {
      const StitchCoord s = g.stitch[i];
      ASSERT_TRUE(s.row >= 0 && s.row < rows && s.col >= 0 && s.col < cols) << "segment " << i;
      if (g.piece[i] == YarnPiece::STITCH) ++per_stitch[{s.row, s.col}];
    }
    EXPECT_EQ(static_cast<int>(per_stitch.size()), rows * cols);
    for (const auto& [rc, n] : per_stitch) EXPECT_EQ(n, k) << rc.first << "," << rc.second;
    EXPECT_TRUE(g.control_points.allFinite());
  }
}

TEST(Generator, ColumnsCountFromTheLeftWhicheverWayTheYarnRuns) {
  const GeneratedKnit g = knit("stockinette", 4, 5);
  std::map<int, double> mean_x;
  std::map<int, int> n;
  for (int i = 0; i < g.num_segments(); ++i)
    if (g.piece[i] == YarnPiece::STITCH) {
      mean_x[g.stitch[i].col] += g.control_points.col(i + 1).x() + g.control_points.col(i + 2).x();
      n[g.stitch[i].col] += 2;
    }
  for (int c = 0; c + 1 < 5; ++c) EXPECT_LT(mean_x[c] / n[c], mean_x[c + 1] / n[c + 1]);
  // rows stack in +y, and the flat piece is centred
  const Eigen::Vector3d centre =
      0.5 * (g.control_points.rowwise().minCoeff() + g.control_points.rowwise().maxCoeff());
  EXPECT_LT(centre.norm(), 1e-9);
}

TEST(Generator, GluesTieEachFreeEndToTheFabric) {
  const std::pair<std::string, bool> cases[] = {
      {"stockinette", false}, {"seed", false}, {"stockinette", true}, {"seed", true}};
  for (const auto& [name, round] : cases) {
    SCOPED_TRACE(name + (round ? " in the round" : " flat"));
    const GeneratedKnit g = knit(name, 4, 4, round);
    ASSERT_EQ(g.glues.size(), 2u);
    const int n = g.num_segments();
    EXPECT_EQ(g.glues[0].a.segment, 0);
    EXPECT_EQ(g.glues[0].a.t, 0.0);
    EXPECT_EQ(g.glues[1].a.segment, n - 1);
    EXPECT_EQ(g.glues[1].a.t, 1.0);
    for (size_t k = 0; k < 2; ++k) {
      const Glue& glue = g.glues[k];
      ASSERT_GE(glue.b.segment, 0);
      ASSERT_LT(glue.b.segment, n);
      ASSERT_GE(glue.b.t, 0.0);
      ASSERT_LE(glue.b.t, 1.0);
      // not in the end's own neighbourhood (its tail and the stitch it enters)
      EXPECT_GT(std::abs(glue.b.segment - glue.a.segment), g.segments_per_tail + 2);
      // the end lies against the fabric: about a yarn diameter from the point it is glued to
      const double gap = (at(g, glue.a) - at(g, glue.b)).norm();
      EXPECT_NEAR(gap, g.glue_gap_cm[k], 1e-9);
      EXPECT_LT(gap, 6 * 0.125) << name << " glue " << k;
      // it is the closest point outside the neighbourhood (checked on a fine sampling)
      for (int i = 0; i < n; ++i) {
        if (std::abs(i - glue.a.segment) <= g.segments_per_tail + 4) continue;
        for (int s = 0; s <= 8; ++s)
          ASSERT_GE((at(g, glue.a) - at(g, {i, s / 8.0})).norm(), gap - 1e-9) << "segment " << i;
      }
    }
    const Model m = build_knit_model(g, Params{});
    EXPECT_EQ(m.glues.size(), 2u);
    EXPECT_TRUE(m.has_stitches());
  }
}

// A bound-off piece: each loop of the last row is tied to the loop below it at two
// points, one on each of its legs, where they cross that loop's head; the yarns there
// touch, about a yarn diameter apart, as laid. A cast-on piece: the same ties one row up
// from the bottom edge, each loop of the second row to the first row's head. Without the
// options the ends' two glues are all.
TEST(Generator, BindOffAndCastOnTieEachEdgeLoopWhereTheLegsCrossTheHeadBelow) {
  for (const std::string name : {"stockinette", "garter", "rib2x2", "seed"})
    for (bool round : {false, true})
      for (bool cast_on : {false, true}) {
        SCOPED_TRACE(name + (round ? " in the round" : " flat") +
                     (cast_on ? ", cast on" : ", bound off"));
        KnitOptions o;
        o.rows = 5;
        o.cols = 6;
        o.in_the_round = round;
        const GeneratedKnit plain = generate_knit(builtin_pattern(name), o);
        (cast_on ? o.cast_on : o.bind_off) = true;
        const GeneratedKnit g = generate_knit(builtin_pattern(name), o);
        const int top_row = cast_on ? 1 : o.rows - 1;
        EXPECT_EQ(plain.glues.size(), 2u);
        ASSERT_EQ(g.glues.size(), 2u + 2 * o.cols);
        ASSERT_EQ(g.glue_gap_cm.size(), g.glues.size());
        EXPECT_EQ(g.control_points, plain.control_points);  // the yarn is the same
        for (int col = 0; col < o.cols; ++col) {
          // the loop below: its height and its middle (a tube's seen around its own angle)
          double lo = 1e9, hi = -1e9, mid_angle = 0;
          Eigen::Vector3d centre = Eigen::Vector3d::Zero();
          int count = 0;
          for (int i = 0; i < g.num_segments(); ++i)
            if (g.piece[i] == YarnPiece::STITCH && g.stitch[i].row == top_row - 1 &&
                g.stitch[i].col == col)
              for (int s = 0; s < 8; ++s) {
                const Eigen::Vector3d x = at(g, {i, s / 8.0});
                lo = std::min(lo, x.y()), hi = std::max(hi, x.y());
                centre += x, ++count;
              }
          centre /= count;
          mid_angle = std::atan2(centre.x(), centre.z());
          auto across = [&](const Eigen::Vector3d& x) {  // along the course from the middle
            return round ? std::remainder(std::atan2(x.x(), x.z()) - mid_angle, 2 * M_PI)
                         : x.x() - centre.x();
          };
          double side[2];
          for (int t = 0; t < 2; ++t) {
            const size_t k = 2 + 2 * col + t;
            const Glue& tie = g.glues[k];
            EXPECT_EQ(g.piece[tie.a.segment], YarnPiece::STITCH);
            EXPECT_EQ(g.piece[tie.b.segment], YarnPiece::STITCH);
            EXPECT_EQ(g.stitch[tie.a.segment].row, top_row);
            EXPECT_EQ(g.stitch[tie.a.segment].col, col);
            EXPECT_EQ(g.stitch[tie.b.segment].row, top_row - 1);
            EXPECT_EQ(g.stitch[tie.b.segment].col, col);
            const Eigen::Vector3d xa = at(g, tie.a), xb = at(g, tie.b);
            EXPECT_NEAR((xa - xb).norm(), g.glue_gap_cm[k], 1e-12);
            // where the yarns cross, touching or nearly (the generator lays them at least 0.9
            // of a diameter apart at its 10 points per segment, and the ties are found among
            // 16, which come up to 0.5 % closer: seed's cast-on ties 0.895; where a rib
            // changes between knit and purl, up to 1.4), on the head of the loop below
            EXPECT_GT(g.glue_gap_cm[k], 0.89 * 2 * o.radius) << "col " << col << " tie " << t;
            EXPECT_LT(g.glue_gap_cm[k], 1.5 * 2 * o.radius) << "col " << col << " tie " << t;
            EXPECT_GT(xb.y(), lo + 0.8 * (hi - lo));
            side[t] = across(xa);
          }
          // one tie on each leg: either side of the loop's middle
          EXPECT_LT(side[0] * side[1], 0) << "col " << col;
        }
        const Model m = build_knit_model(g, Params{});
        EXPECT_EQ(m.glues.size(), g.glues.size());
      }
  // both: the bind-off's ties, then the cast-on's
  KnitOptions both;
  both.rows = 5;
  both.cols = 6;
  both.bind_off = both.cast_on = true;
  const GeneratedKnit g = generate_knit(builtin_pattern("stockinette"), both);
  ASSERT_EQ(g.glues.size(), 2u + 4 * both.cols);
  EXPECT_EQ(g.stitch[g.glues[2].a.segment].row, both.rows - 1);
  EXPECT_EQ(g.stitch[g.glues[2 + 2 * both.cols].a.segment].row, 1);
  // with 2 rows the bind-off's ties are the cast-on's: tied once
  both.rows = 2;
  EXPECT_EQ(generate_knit(builtin_pattern("stockinette"), both).glues.size(), 2u + 2 * both.cols);
  KnitOptions one_row;
  one_row.rows = 1;
  one_row.bind_off = true;
  EXPECT_THROW(
      {
        try {
          generate_knit(builtin_pattern("stockinette"), one_row);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("bind_off needs at least 2 rows"),
                    std::string::npos);
          throw;
        }
      },
      std::invalid_argument);
  one_row.bind_off = false;
  one_row.cast_on = true;
  EXPECT_THROW(
      {
        try {
          generate_knit(builtin_pattern("stockinette"), one_row);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("cast_on needs at least 2 rows"), std::string::npos);
          throw;
        }
      },
      std::invalid_argument);
}

// The fitted yarn keeps its distance: no two non-neighbouring segments closer than the
// bound reached by the generator (1 would be touching tubes). The flat stockinette, garter
// and ribs keep what the loop model lays (its plain loop comes within 0.918 of itself);
// seed and tubes, where the model lays yarns closer, are pushed apart to 0.9.
TEST(Generator, EveryPatternKeepsItsDistanceFlatAndInTheRound) {
  const struct {
    const char* name;
    double flat, round;
  } cases[] = {{"stockinette", 0.915, 0.915}, {"reverse_stockinette", 0.915, 0.915},
               {"garter", 0.915, 0.9},        {"rib1x1", 0.97, 0.9},
               {"rib2x2", 0.93, 0.9},         {"seed", 0.9, 0.9}};
  std::set<std::string> covered;
  for (const auto& c : cases)
    for (bool round : {false, true}) {
      covered.insert(c.name);
      const GeneratedKnit g = knit(c.name, 6, 6, round);
      EXPECT_GE(g.min_distance_ratio, round ? c.round : c.flat)
          << c.name << (round ? " in the round" : " flat") << ": closest segments "
          << g.min_distance_segment_a << " and " << g.min_distance_segment_b;
    }
  EXPECT_EQ(covered.size(), builtin_pattern_names().size());
}

TEST(Generator, GridMinimumDistanceMatchesBruteForce) {
  for (const std::string name : {"stockinette", "seed"}) {
    const GeneratedKnit g = knit(name, 4, 5);
    const MinDistance fast = min_distance(g.control_points, 0.125);
    const MinDistance slow = min_distance_brute_force(g.control_points, 0.125);
    EXPECT_DOUBLE_EQ(fast.ratio, slow.ratio) << name;
    EXPECT_DOUBLE_EQ(fast.ratio, g.min_distance_ratio);
  }
  // a straight yarn: nothing close, the grid falls back to all pairs
  Eigen::Matrix3Xd line(3, 12);
  for (int k = 0; k < 12; ++k) line.col(k) = Eigen::Vector3d(k, 0, 0);
  EXPECT_NEAR(min_distance(line, 0.125).ratio, min_distance_brute_force(line, 0.125).ratio, 1e-12);
  EXPECT_GT(min_distance(line, 0.125).ratio, 1.0);
}

TEST(Generator, OptionsAreCheckedAndStitchSizeScalesTheLoop) {
  KnitOptions bad;
  bad.rows = 0;
  EXPECT_THROW(generate_knit(builtin_pattern("garter"), bad), std::invalid_argument);
  bad = KnitOptions{};
  bad.segments_per_stitch = 2;
  EXPECT_THROW(generate_knit(builtin_pattern("garter"), bad), std::invalid_argument);
  bad = KnitOptions{};
  bad.stitch_size_cm = -1;
  try {
    generate_knit(builtin_pattern("garter"), bad);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("stitch_size_cm"), std::string::npos);
  }
  KnitOptions o;
  o.rows = o.cols = 4;
  const GeneratedKnit base = generate_knit(builtin_pattern("stockinette"), o);
  o.stitch_size_cm = 1.25 * base.loop_length_cm;
  const GeneratedKnit big = generate_knit(builtin_pattern("stockinette"), o);
  EXPECT_NEAR(big.loop_length_cm, o.stitch_size_cm, 0.03 * o.stitch_size_cm);
  EXPECT_GT(big.stitch_width_cm, 1.2 * base.stitch_width_cm);
  EXPECT_GT(big.row_height_cm, 1.2 * base.row_height_cm);
  EXPECT_GE(big.min_distance_ratio, base.min_distance_ratio - 0.05);
}

// --- interlocking, checked on the geometry -------------------------------------------

struct Crossing {
  double y_old;  // height of the crossing on the older loop, relative to that loop
  double dz;     // z(new loop) − z(old loop) where they cross, seen from the front
};

Eigen::Matrix3Xd loop_polyline(const GeneratedKnit& g, int row, int col) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < g.num_segments(); ++i)
    if (g.piece[i] == YarnPiece::STITCH && g.stitch[i].row == row && g.stitch[i].col == col)
      for (int s = 0; s < 24; ++s)
        pts.push_back(g.control_points.middleCols<4>(i) * bspline_basis(s / 24.0));
  Eigen::Matrix3Xd p(3, pts.size());
  for (size_t j = 0; j < pts.size(); ++j) p.col(j) = pts[j];
  return p;
}

// A tube (axis y, front face outside) unrolled around the angle `theta_ref`: x becomes the
// arc length at `radius`, z the distance outside that radius.
Eigen::Matrix3Xd unrolled(const Eigen::Matrix3Xd& p, double theta_ref, double radius) {
  Eigen::Matrix3Xd u(3, p.cols());
  for (int j = 0; j < p.cols(); ++j) {
    const double theta =
        theta_ref + std::remainder(std::atan2(p(0, j), p(2, j)) - theta_ref, 2 * M_PI);
    u.col(j) = Eigen::Vector3d(radius * theta, p(1, j), std::hypot(p(0, j), p(2, j)) - radius);
  }
  return u;
}

// crossings of the front views (xy) of the loop of (row, col) and the one below it; a tube
// is first unrolled around the loop below
std::vector<Crossing> crossings(const GeneratedKnit& g, int row, int col, bool round) {
  Eigen::Matrix3Xd a = loop_polyline(g, row, col), b = loop_polyline(g, row - 1, col);
  if (round) {
    const Eigen::Vector3d centre = b.rowwise().mean();
    const double theta = std::atan2(centre.x(), centre.z());
    const double radius = std::hypot(centre.x(), centre.z());
    a = unrolled(a, theta, radius);
    b = unrolled(b, theta, radius);
  }
  const double top = b.row(1).maxCoeff(), bottom = b.row(1).minCoeff();
  const double mid = 0.5 * (top + bottom), half = 0.5 * (top - bottom);
  std::vector<Crossing> out;
  for (int i = 0; i + 1 < a.cols(); ++i)
    for (int j = 0; j + 1 < b.cols(); ++j) {
      const Eigen::Vector2d p = a.col(i).head<2>(), r = a.col(i + 1).head<2>() - p;
      const Eigen::Vector2d q = b.col(j).head<2>(), s = b.col(j + 1).head<2>() - q;
      const double den = r.x() * s.y() - r.y() * s.x();
      if (std::abs(den) < 1e-14) continue;
      const Eigen::Vector2d d = q - p;
      const double u = (d.x() * s.y() - d.y() * s.x()) / den;
      const double v = (d.x() * r.y() - d.y() * r.x()) / den;
      if (u < 0 || u >= 1 || v < 0 || v >= 1) continue;
      const double za = a(2, i) + u * (a(2, i + 1) - a(2, i));
      const double zb = b(2, j) + v * (b(2, j + 1) - b(2, j));
      const double yb = b(1, j) + v * (b(1, j + 1) - b(1, j));
      out.push_back({(yb - mid) / half, za - zb});
    }
  return out;
}

// For every stitch above row 0: where its loop crosses the HEAD of the loop below (top of
// that loop), its legs pass in front (+z) for a knit and behind for a purl, as seen from
// the front; where its foot crosses the legs of the loop below, the other way round.
// Returns the stitches that break this (or do not pass through the loop below at all).
std::vector<std::string> interlock_errors(const GeneratedKnit& g, const Pattern& pattern,
                                          bool round = false) {
  std::vector<std::string> errors;
  for (int row = 1; row < pattern.num_rows(); ++row)
    for (int col = 0; col < pattern.num_cols(); ++col) {
      const double sigma = pattern.is_knit(row, col) ? 1 : -1;
      const std::string where = "stitch (" + std::to_string(row) + "," + std::to_string(col) +
                                ") " + pattern.rows[row][col] + ": ";
      int heads = 0, legs = 0;
      for (const Crossing& c : crossings(g, row, col, round)) {
        if (c.y_old > 0.6) {
          ++heads;
          if (!(sigma * c.dz > 0))
            errors.push_back(where + "legs on the wrong side of the head below");
        } else {
          ++legs;
          if (!(sigma * c.dz < 0))
            errors.push_back(where + "foot on the wrong side of the legs below");
        }
      }
      if (heads < 2 || legs < 2) errors.push_back(where + "not pulled through the loop below");
    }
  return errors;
}

void expect_interlocked_as(const GeneratedKnit& g, const Pattern& pattern, bool round = false) {
  const auto errors = interlock_errors(g, pattern, round);
  EXPECT_TRUE(errors.empty()) << errors.size() << " errors, first: " << errors.front();
}

TEST(Generator, StockinetteLoopsAllPullThroughToTheFrontThoughTheYarnTurns) {
  // odd rows run right to left: still every loop comes through to the front face
  const GeneratedKnit g = knit("stockinette", 6, 6);
  expect_interlocked_as(g, tile(builtin_pattern("stockinette"), 6, 6));
  // the check itself tells the faces apart: this geometry is not reverse stockinette,
  // and not garter on the odd rows
  EXPECT_EQ(interlock_errors(g, tile(builtin_pattern("reverse_stockinette"), 6, 6)).size(),
            4u * 5 * 6);
  EXPECT_EQ(interlock_errors(g, tile(builtin_pattern("garter"), 6, 6)).size(), 4u * 3 * 6);
}

TEST(Generator, KnitAndPurlInterlockAsThePatternSays) {
  for (const std::string name : {"garter", "rib2x2", "rib1x1", "seed", "reverse_stockinette"}) {
    SCOPED_TRACE(name);
    const GeneratedKnit g = knit(name, 6, 6);
    expect_interlocked_as(g, tile(builtin_pattern(name), 6, 6));
  }
  const Pattern chart = load_pattern(std::string(KNIT_TEST_DATA) + "/patterns/rib_and_seed.chart");
  KnitOptions o;
  o.rows = 6;
  o.cols = 8;
  expect_interlocked_as(generate_knit(chart, o), tile(chart, 6, 8));
}

// A tube's rows form a helix: the last stitch of each round meets the first of the next
// at a seam, where garter changes between knit and purl and seed and the ribs change
// column; every loop, the seam's included, still comes through the one below as charted.
TEST(Generator, TubesInterlockAsThePatternSays) {
  for (const std::string& name : builtin_pattern_names()) {
    SCOPED_TRACE(name);
    const GeneratedKnit g = knit(name, 6, 6, true);
    expect_interlocked_as(g, tile(builtin_pattern(name), 6, 6), true);
  }
  // the unrolled check tells the faces apart on a tube too
  const GeneratedKnit g = knit("stockinette", 6, 6, true);
  EXPECT_EQ(interlock_errors(g, tile(builtin_pattern("reverse_stockinette"), 6, 6), true).size(),
            4u * 5 * 6);
}

}  // namespace
}  // namespace knit
