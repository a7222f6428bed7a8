// The crossing check (contact/crossings.hpp): moving edges that pass through each other,
// checked against the analytic answer and against independent oracles (the sampled height
// of one edge's point on the other's line; the linking number of two closed rings, which
// changes by one at each crossing); yarns of a model moved through each other by hand;
// and physics: a yarn shot at another is stopped by contact (no crossing at any step) and
// with contact off flies through it, found when and where the flight says.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "knit/contact/crossings.hpp"
#include "knit/model/model.hpp"
#include "knit/recipes/relax_knit.hpp"
#include "knit/run/runner.hpp"
#include "knit/solver/simulator.hpp"
#include "knit/spline/basis.hpp"
#include "yarn_setups.hpp"

namespace knit {
namespace {

using Eigen::Vector3d;

MovingEdge moving(const Vector3d& p0, const Vector3d& p1, const Vector3d& d) {
  return {p0, p1, d, d};
}

TEST(EdgeCrossings, AnEdgeMovedThroughAnotherCrossesItWhereAndWhenTheyMeet) {
  const MovingEdge a = moving({-1, 0, 0}, {1, 0, 0}, Vector3d::Zero());
  // along y at z = 1, moved to z = −1 (it meets a at z = 0, halfway), at x = 0.4
  const MovingEdge b = moving({0.4, -1, 1}, {0.4, 1, 1}, {0, 0, -2});
  const auto c = edge_crossings(a, b);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_NEAR(c[0].s, 0.5, 1e-12);
  EXPECT_NEAR(c[0].u, 0.7, 1e-12);  // x = 0.4 on [−1, 1]
  EXPECT_NEAR(c[0].v, 0.5, 1e-12);
  // the same seen from b, and the motion reversed (b from below): found alike
  EXPECT_EQ(edge_crossings(b, a).size(), 1u);
  const MovingEdge up = moving({0.4, -1, -1}, {0.4, 1, -1}, {0, 0, 2});
  EXPECT_EQ(edge_crossings(a, up).size(), 1u);
  // a moved instead of b: the same crossing
  const MovingEdge a_moving = moving({-1, 0, 0}, {1, 0, 0}, {0, 0, 2});
  EXPECT_EQ(edge_crossings(a_moving, moving({0.4, -1, 1}, {0.4, 1, 1}, Vector3d::Zero())).size(),
            1u);
}

TEST(EdgeCrossings, EdgesThatPassBesideStopShortOrRunParallelDoNotCross) {
  const MovingEdge a = moving({-1, 0, 0}, {1, 0, 0}, Vector3d::Zero());
  // beyond a's end (x = 1.2): the lines cross, the edges do not
  EXPECT_TRUE(edge_crossings(a, moving({1.2, -1, 1}, {1.2, 1, 1}, {0, 0, -2})).empty());
  // beyond b's end: b spans y ∈ [0.1, 1]
  EXPECT_TRUE(edge_crossings(a, moving({0, 0.1, 1}, {0, 1, 1}, {0, 0, -2})).empty());
  // stops short of a (z from 1 to 0.01)
  EXPECT_TRUE(edge_crossings(a, moving({0, -1, 1}, {0, 1, 1}, {0, 0, -0.99})).empty());
  // parallel to a, moved through its line's plane
  EXPECT_TRUE(edge_crossings(a, moving({-1, 0, 1}, {1, 0, 1}, {0, 0, -2})).empty());
  // not moving at all
  EXPECT_TRUE(edge_crossings(a, moving({0, -1, 1}, {0, 1, 1}, Vector3d::Zero())).empty());
}

TEST(EdgeCrossings, AnEdgeThatPassesThroughAnotherAndBackCrossesTwice) {
  // a along x; b in the plane x = 0, sliding along y by −1 while its ends move in z, so
  // that its point at y = 0 (where it would meet a) has height N(s)/2 with
  // N(s) = z0 y1 − z1 y0 = (s − ¼)(s − ¾): b passes down through a at s = ¼ and back up
  // at s = ¾, meeting it at x = 0 (u = ½) and at v = (½ + s)/2 along itself
  const MovingEdge a = moving({-3, 0, 0}, {3, 0, 0}, Vector3d::Zero());
  MovingEdge b;
  b.p0 = {0, -0.5, 0.125};
  b.d0 = {0, -1, -0.6875};
  b.p1 = {0, 1.5, 0};
  b.d1 = {0, -1, 0.3125};
  const auto c = edge_crossings(a, b);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_NEAR(c[0].s, 0.25, 1e-12);
  EXPECT_NEAR(c[1].s, 0.75, 1e-12);
  EXPECT_NEAR(c[0].u, 0.5, 1e-12);
  EXPECT_NEAR(c[0].v, 0.375, 1e-12);
  EXPECT_NEAR(c[1].v, 0.625, 1e-12);
}

// A randomised check of edge_crossings against the sampled height of b's point on a's
// line: for a static a along x and b moving anywhere, b passes through a exactly where
// that height changes sign with the point within both edges.
TEST(EdgeCrossings, AgreeWithAFinelySampledOracle) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  const MovingEdge a = moving({-1, 0, 0}, {1, 0, 0}, Vector3d::Zero());
  int total = 0;
  for (int trial = 0; trial < 200; ++trial) {
    MovingEdge b;
    b.p0 = Vector3d(U(rng), -1 + 0.5 * U(rng), U(rng));
    b.p1 = Vector3d(U(rng), 1 + 0.5 * U(rng), U(rng));
    b.d0 = 2 * Vector3d(U(rng), 0.3 * U(rng), U(rng));
    b.d1 = 2 * Vector3d(U(rng), 0.3 * U(rng), U(rng));
    int oracle = 0;
    bool near_end = false;  // a crossing within a sample of a's end may fall either way
    const int n = 20000;
    double z_prev = 0;
    for (int k = 0; k <= n; ++k) {
      const double s = static_cast<double>(k) / n;
      const Vector3d p0 = b.p0 + s * b.d0, p1 = b.p1 + s * b.d1;
      // b's point at y = 0 (b always spans y = 0 here: its ends stay on either side)
      const double v = -p0.y() / (p1.y() - p0.y());
      const Vector3d p = p0 + v * (p1 - p0);
      if (k > 0 && (p.z() > 0) != (z_prev > 0)) {
        near_end |= std::abs(std::abs(p.x()) - 1) < 1e-2;
        oracle += std::abs(p.x()) <= 1;
      }
      z_prev = p.z();
    }
    const auto found = edge_crossings(a, b);
    for (const auto& c : found) near_end |= c.u < 5e-3 || c.u > 1 - 5e-3;
    if (!near_end) {
      EXPECT_EQ(static_cast<int>(found.size()), oracle) << "trial " << trial;
    }
    total += static_cast<int>(found.size());
  }
  EXPECT_GT(total, 40);  // the trials cross often
}

// ---- the oracle: two closed rings and their linking number ----

using Ring = std::vector<Vector3d>;

Ring circle(const Vector3d& centre, const Eigen::Matrix3d& frame, double radius, int n) {
  Ring r;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * M_PI * k / n;
    r.push_back(centre + frame * Vector3d(radius * std::cos(t), radius * std::sin(t), 0));
  }
  return r;
}

// The linking number of two closed polygons from their projection onto the xy plane:
// the signed crossings where `a` passes over `b` (an independent computation: 2D segment
// intersections and heights only).
int linking_number(const Ring& a, const Ring& b) {
  int lk = 0;
  const int na = static_cast<int>(a.size()), nb = static_cast<int>(b.size());
  for (int i = 0; i < na; ++i) {
    const Vector3d &p = a[i], &q = a[(i + 1) % na];
    for (int j = 0; j < nb; ++j) {
      const Vector3d &r = b[j], &s = b[(j + 1) % nb];
      const Eigen::Vector2d d1 = (q - p).head<2>(), d2 = (s - r).head<2>(), w = (r - p).head<2>();
      const double den = d1.x() * d2.y() - d1.y() * d2.x();
      if (den == 0) continue;
      const double t = (w.x() * d2.y() - w.y() * d2.x()) / den;
      const double u = (w.x() * d1.y() - w.y() * d1.x()) / den;
      if (t < 0 || t >= 1 || u < 0 || u >= 1) continue;
      const double za = p.z() + t * (q.z() - p.z()), zb = r.z() + u * (s.z() - r.z());
      if (za > zb) lk += den > 0 ? 1 : -1;
    }
  }
  return lk;
}

TEST(EdgeCrossings, EveryChangeOfTwoRingsLinkingNumberIsACrossingFound) {
  std::mt19937 rng(20261207);
  std::uniform_real_distribution<double> U(-1, 1);
  auto random_frame = [&] {
    return Eigen::Quaterniond(Vector3d(U(rng), U(rng), U(rng)).normalized().x(), U(rng), U(rng),
                              U(rng))
        .normalized()
        .toRotationMatrix();
  };
  int changed = 0, trials = 400, with_crossings = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const int n = 12;
    const Ring a0 = circle(Vector3d::Zero(), random_frame(), 1.0, n);
    // b: a ring through or beside a, moved by a random translation and its vertices
    // jittered independently (each still moves on a straight line)
    const Ring b0 = circle(Vector3d(U(rng), U(rng), U(rng)), random_frame(), 0.8, n);
    const Vector3d shift(1.5 * U(rng), 1.5 * U(rng), 1.5 * U(rng));
    Ring b1 = b0, a1 = a0;
    for (auto& p : b1) p += shift + 0.1 * Vector3d(U(rng), U(rng), U(rng));
    for (auto& p : a1) p += 0.1 * Vector3d(U(rng), U(rng), U(rng));
    int found = 0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const MovingEdge ea{a0[i], a0[(i + 1) % n], a1[i] - a0[i],
                            a1[(i + 1) % n] - a0[(i + 1) % n]};
        const MovingEdge eb{b0[j], b0[(j + 1) % n], b1[j] - b0[j],
                            b1[(j + 1) % n] - b0[(j + 1) % n]};
        found += static_cast<int>(edge_crossings(ea, eb).size());
      }
    const int dlk = linking_number(a1, b1) - linking_number(a0, b0);
    // each crossing changes the linking number by ±1
    EXPECT_EQ(((found - dlk) % 2 + 2) % 2, 0)
        << "trial " << trial << ": " << found << " crossings, linking number changed by " << dlk;
    EXPECT_GE(found, std::abs(dlk)) << "trial " << trial;
    changed += dlk != 0;
    with_crossings += found > 0;
  }
  // the trials exercise both outcomes
  EXPECT_GT(changed, trials / 10);
  EXPECT_LT(with_crossings, trials * 9 / 10);
}

// ---- yarns of a model ----

// two straight yarns of 8 segments, 4 cm long, in `b`: a along x at z = 0, b along y at
// z = height, crossing (seen from above) at x = y = 0.25, the middle of a segment of each
void add_crossed_yarns(ModelBuilder& b, double height) {
  Eigen::Matrix3Xd ya = test::line(8, 4.0), yb = test::line(8, 4.0);
  ya.row(0).array() -= 2;
  ya.row(1).setConstant(0.25);
  yb.row(0).array() -= 2;
  yb.row(1) = yb.row(0);
  yb.row(0).setConstant(0.25);
  yb.row(2).setConstant(height);
  b.add_yarn(ya);
  b.add_yarn(yb);
}

// the two yarns, b 1 cm above a
Model two_yarns(Eigen::VectorXd& q) {
  ModelBuilder b;
  add_crossed_yarns(b, 1.0);
  Params p;
  Model m = b.build(p);
  q = b.positions();
  return m;
}

TEST(FindCrossings, AYarnMovedThroughAnotherIsFoundAtTheSegmentsThatMet) {
  Eigen::VectorXd q0;
  const Model m = two_yarns(q0);
  Eigen::VectorXd q1 = q0;
  for (int cp = m.yarns[1].cp_begin; cp < m.yarns[1].cp_end; ++cp) q1[3 * cp + 2] -= 2;
  const auto c = find_crossings(m, q0, q1);
  ASSERT_EQ(c.size(), 1u);
  // which segment holds x = 0.25 on a (and y = 0.25 on b): where the splines are at 0.25
  auto segment_at = [&](int yarn, int axis) {
    for (int i = m.yarns[yarn].seg_begin; i < m.yarns[yarn].seg_end; ++i) {
      const Vector12d x = gather_segment(q0, m.seg_cp[i]);
      if (combine(x, bspline_basis(0))[axis] <= 0.25 && combine(x, bspline_basis(1))[axis] > 0.25)
        return i;
    }
    return -1;
  };
  EXPECT_EQ(c[0].segment_a, segment_at(0, 0));
  EXPECT_EQ(c[0].segment_b, segment_at(1, 1));
  EXPECT_NEAR(c[0].step_fraction, 0.5, 1e-9);
  EXPECT_NEAR(c[0].point.x(), 0.25, 1e-6);
  EXPECT_NEAR(c[0].point.y(), 0.25, 1e-6);
  // stopped short (to z = 0.05) or moved back: nothing
  Eigen::VectorXd q_short = q0;
  for (int cp = m.yarns[1].cp_begin; cp < m.yarns[1].cp_end; ++cp) q_short[3 * cp + 2] -= 0.95;
  EXPECT_TRUE(find_crossings(m, q0, q_short).empty());
  EXPECT_EQ(find_crossings(m, q1, q0).size(), 1u);
  EXPECT_TRUE(find_crossings(m, q0, q0).empty());
}

TEST(FindCrossings, AYarnFoldedThroughItselfIsFound) {
  // a hairpin whose returning arm, above the first, swings across and below it
  ModelBuilder b;
  // a hairpin: out along x at z = 0, back along x at y = 0.6, z = 0.5 (above the first arm)
  Eigen::Matrix3Xd hair(3, 15);
  for (int k = 0; k < 15; ++k) {
    const double x = (k - 1) * 0.5;
    hair.col(k) = k < 8 ? Vector3d(x, 0, 0) : Vector3d(3.0 - (x - 3.0), 0.6, 0.5);
  }
  hair.col(7) = Vector3d(3.2, 0.3, 0.25);  // the bend
  b.add_yarn(hair);
  Params p;
  const Model m = b.build(p);
  const Eigen::VectorXd q0 = b.positions();
  Eigen::VectorXd q1 = q0;
  // the returning arm swung sideways across the first (y from 0.6 to −0.6) and down
  for (int k = 10; k < 15; ++k) {
    q1[3 * k + 1] = -0.6;
    q1[3 * k + 2] = -0.5;
  }
  EXPECT_FALSE(find_crossings(m, q0, q1).empty());
}

TEST(FindCrossings, BadInputIsRefused) {
  Eigen::VectorXd q0;
  const Model m = two_yarns(q0);
  EXPECT_THROW(find_crossings(m, q0, Eigen::VectorXd::Zero(3)), std::invalid_argument);
  EXPECT_THROW(find_crossings(m, q0, q0, 0), std::invalid_argument);
}

// ---- physics: contact stops a yarn shot at another; without contact it flies through ----

// yarn a pinned at both ends along x; yarn b along y, SHOT_HEIGHT above, flying down at
// SHOT_SPEED
constexpr double SHOT_SPEED = 30, SHOT_HEIGHT = 1.0;
Model shot_yarn(State& s) {
  ModelBuilder b;
  add_crossed_yarns(b, SHOT_HEIGHT);
  Params p;
  p.gravity.setZero();
  b.add_pin({{0, 0.0}, Vector3d::Zero()});
  b.add_pin({{7, 1.0}, Vector3d::Zero()});
  Model m = b.build(p);
  m.pins[0].origin = point_position(m, b.positions(), {0, 0.0});
  m.pins[1].origin = point_position(m, b.positions(), {7, 1.0});
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  for (int cp = m.yarns[1].cp_begin; cp < m.yarns[1].cp_end; ++cp) s.v[3 * cp + 2] = -SHOT_SPEED;
  return m;
}

// A yarn shot at another: contact stops it and bounces it back (no crossing at any step);
// with contact off it flies through, and the check finds the one crossing when the
// analytic flight says (b's height reaches a's at t = height / speed).
TEST(FindCrossings, AYarnShotAtAnotherIsStoppedByContactAndFliesThroughWithoutIt) {
  const double h = 1.0 / 11800;
  for (const bool contact : {true, false}) {
    State s;
    Model m = shot_yarn(s);
    m.params.material.contact = contact;
    Simulator sim(std::move(m));
    ASSERT_TRUE(sim.satisfy_constraints(s).converged);
    const int steps = static_cast<int>(std::lround(0.06 / h));
    std::vector<SegmentCrossing> all;
    std::vector<double> when;
    for (int k = 0; k < steps; ++k) {
      const Eigen::VectorXd before = s.q;
      const double t0 = s.time;
      ASSERT_TRUE(sim.step(s, h).ok()) << "step " << k;
      for (const SegmentCrossing& c : find_crossings(sim.model(), before, s.q)) {
        all.push_back(c);
        when.push_back(t0 + c.step_fraction * h);
      }
    }
    // where b's middle is at the end: above a (stopped) or below it (through)
    const double z_mid = s.q[3 * (sim.model().yarns[1].cp_begin + 5) + 2];
    if (contact) {
      EXPECT_TRUE(all.empty()) << all.size() << " crossings, the first at t = " << when[0];
      EXPECT_GT(z_mid, 0) << "contact stops b above a";
    } else {
      ASSERT_EQ(all.size(), 1u);
      EXPECT_LT(z_mid, 0) << "b flew through a";
      EXPECT_NEAR(when[0], SHOT_HEIGHT / SHOT_SPEED, 1e-6);
      EXPECT_EQ(sim.model().seg_yarn[all[0].segment_a], 0);
      EXPECT_EQ(sim.model().seg_yarn[all[0].segment_b], 1);
      EXPECT_NEAR(all[0].point.x(), 0.25, 1e-3);
      EXPECT_NEAR(all[0].point.y(), 0.25, 1e-3);
    }
  }
}

// The shot yarn run for 0.05 s with contact on or off, crossings refused (with `halvings`)
// or counted (check); `z_mid`: the height of b's middle at the end, and the summary's
// test_state_time_s the time of the state the run ended with.
RunReport run_shot(bool contact, bool refuse, int halvings, bool check, double& z_mid) {
  State s;
  Model m = shot_yarn(s);
  m.params.material.contact = contact;
  m.params.solver.refuse_crossings = refuse;
  m.params.solver.max_step_halvings = halvings;
  Simulator sim(std::move(m));
  EXPECT_TRUE(sim.satisfy_constraints(s).converged);
  RunOptions o;
  o.duration = 0.05;
  o.progress = false;
  o.output_every = 50;
  o.check_crossings = check;
  RunReport r = run_simulation(sim, s, o);
  z_mid = s.q[3 * (sim.model().yarns[1].cp_begin + 5) + 2];
  r.summary["test_state_time_s"] = s.time;  // (the state it ended with)
  return r;
}

// With refuse_crossings a step in which the yarns pass through each other fails ("crossed",
// naming the segments), leaving the state before it; step halving takes it again in
// halves, and fails too when nothing stops the yarn (contact off: it flies through at any
// step). With contact the run never fails: contact stops the yarn.
TEST(FindCrossings, ARefusedCrossingFailsTheStepThatMadeIt) {
  const double h = Params{}.solver.time_step;
  double z_mid = 0;
  for (const int halvings : {0, 3}) {
    const RunReport r = run_shot(false, true, halvings, false, z_mid);
    EXPECT_EQ(r.status, StepStatus::CROSSED) << r.message;
    EXPECT_EQ(r.summary.at("status"), "crossed");
    EXPECT_NE(r.message.find("yarns passed through each other"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("(yarn 0) and segment"), std::string::npos) << r.message;
    // the run stops with b still above a, within a step of the flight's crossing time
    const double t = r.summary.at("test_state_time_s").get<double>();
    EXPECT_LE(t, SHOT_HEIGHT / SHOT_SPEED + 1e-12);
    EXPECT_GT(t, SHOT_HEIGHT / SHOT_SPEED - h);
    EXPECT_GT(z_mid, 0);
    if (halvings > 0) {
      EXPECT_NE(r.message.find("halv"), std::string::npos) << r.message;
    }
  }
  EXPECT_EQ(run_shot(true, true, 0, false, z_mid).status, StepStatus::OK);
  EXPECT_GT(z_mid, 0);
}

// the runner checks every step when asked (--check-crossings) and says what it found
TEST(FindCrossings, ARunChecksEveryStepAndItsSummarySaysWhatItFound) {
  double z_mid = 0;
  for (const bool contact : {true, false}) {
    const RunReport r = run_shot(contact, false, 0, true, z_mid);
    ASSERT_EQ(r.status, StepStatus::OK) << r.message;
    const auto& c = r.summary.at("crossings");
    EXPECT_EQ(c.at("steps_checked").get<long long>(), r.steps);
    if (contact) {
      EXPECT_EQ(c.at("count").get<long long>(), 0);
      EXPECT_TRUE(c.at("first").is_null());
    } else {
      EXPECT_EQ(c.at("count").get<long long>(), 1);
      EXPECT_NEAR(c.at("first").at("time_s").get<double>(), SHOT_HEIGHT / SHOT_SPEED, 1e-6);
      EXPECT_EQ(c.at("first").at("yarns"), nlohmann::json::array({0, 1}));
    }
  }
  // without the option, no block
  EXPECT_FALSE(run_shot(true, false, 0, false, z_mid).summary.contains("crossings"));
}

// Knits relax without a yarn passing through another: each of the built-in patterns (flat)
// and a tube, 4×4, over 0.02 s (236 steps) of relaxation as `knitsim relax` runs it, every
// step checked; their glued ends excepted (a glue may pull its end through, see
// crossings.hpp).
TEST(FindCrossings, KnitsRelaxWithoutAYarnPassingThroughAnother) {
  for (const std::string pattern : {"stockinette", "garter", "rib2x2", "seed"})
    for (const bool round : {false, true}) {
      if (round && pattern != "stockinette") continue;
      RelaxKnitOptions o;
      o.knit.rows = 4;
      o.knit.cols = 4;
      o.knit.in_the_round = round;
      o.run.max_time = 0.02;
      o.run.progress = false;
      o.run.check_crossings = true;
      const RelaxResult r = relax_knit(pattern, o);
      ASSERT_EQ(r.report.status, StepStatus::OK) << pattern << ": " << r.report.message;
      const auto& c = r.report.summary.at("crossings");
      EXPECT_EQ(c.at("steps_checked").get<long long>(), r.report.steps) << pattern;
      EXPECT_EQ(c.at("count").get<long long>(), 0)
          << pattern << (round ? " (round)" : "") << ": " << c.dump();
    }
}

}  // namespace
}  // namespace knit
