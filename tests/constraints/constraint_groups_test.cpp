// Constraint groups report the forces they exert (StepData's ConstraintRecord), checked
// against answers from mechanics: a hanging yarn's pin carries its weight, two clamps
// holding a yarn at rest balance its weight and each other, and the momentum of a yarn
// pulled about by clamps changes by exactly the external forces (Newton's second law).
#include <gtest/gtest.h>

#include "knit/constraints/groups.hpp"
#include "knit/model/model.hpp"
#include "knit/solver/simulator.hpp"

namespace knit {
namespace {

// control points of a straight yarn from a to b with `segments` segments
Eigen::Matrix3Xd line(const Eigen::Vector3d& a, const Eigen::Vector3d& b, int segments) {
  Eigen::Matrix3Xd cp(3, segments + 3);
  for (int k = 0; k < segments + 3; ++k) cp.col(k) = a + (k - 1) * (b - a) / segments;
  return cp;
}

State rest_state(const ModelBuilder& b) {
  State s;
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  return s;
}

// the group's force averaged over `steps` further steps (the projection's per-step force
// carries an O(h) ripple at rest)
Eigen::Vector3d mean_force(Simulator& sim, State& s, const std::string& group, int steps) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i = 0; i < steps; ++i) {
    EXPECT_TRUE(sim.step(s).ok());
    const ConstraintRecord* c = sim.data().constraint(group);
    EXPECT_NE(c, nullptr) << group;
    if (c) sum += c->force;
  }
  return sum / steps;
}

TEST(ConstraintGroups, HangingYarnsPinCarriesItsWeight) {
  ModelBuilder b;
  b.add_yarn(line({0, 0, 0}, {0.3, 0, -10}, 24));
  Pin pin;
  pin.at = {0, 0.0};
  pin.origin = point_position(ModelBuilder(b).build(Params{}), b.positions(), pin.at);
  b.add_pin(pin);
  // light global damping brings it to rest; it also carries a part ∝ k_global·h of the
  // load, through the O(h·g) velocity the projection leaves on a resting yarn (0.4 % here)
  Params p;
  p.material.k_global = 0.05;
  p.material.contact = false;
  p.solver.time_step = 1e-4;
  Simulator sim(b.build(p));
  State s = rest_state(b);
  for (int i = 0; i < 30000; ++i) ASSERT_TRUE(sim.step(s).ok()) << i;  // 3 s
  const Eigen::Vector3d f = mean_force(sim, s, "pin0", 200);
  const double weight = sim.model().mass.sum() * 981;
  // the pin holds the yarn up: +weight along z, nothing sideways
  EXPECT_NEAR(f.z(), weight, 0.01 * weight) << f.transpose();
  EXPECT_LT(f.head<2>().norm(), 0.01 * weight) << f.transpose();
  const ConstraintRecord& rec = *sim.data().constraint("pin0");
  EXPECT_EQ(rec.kind, "pin");
  EXPECT_EQ(rec.rows, 3);
  EXPECT_LT(rec.max_violation, p.solver.constraint_tolerance);
}

// a yarn held at both ends by clamps (three knots each), laid in a sag (8 cm apart, 4.5 cm
// deep: slack for the ends to move)
struct TwoClamps {
  TwoClamps(std::vector<Keyframe> right_motion = {}, double k_global = 0.05) {
    Eigen::Matrix3Xd cp(3, 35);
    for (int k = 0; k < 35; ++k)
      cp.col(k) = Eigen::Vector3d(0.25 * (k - 1), 0, -0.02 * (k - 1) * (31 - k));
    b.add_yarn(cp);
    Clamp left, right;
    left.name = "left";
    right.name = "right";
    for (int i = 0; i < 3; ++i) {
      left.points.push_back({i, 0.0});
      right.points.push_back({31 - i, 1.0});
    }
    right.keyframes = std::move(right_motion);
    b.add_clamp(left);
    b.add_clamp(right);
    Params p;
    p.material.k_global = k_global;
    p.material.contact = false;
    p.solver.time_step = 1e-4;
    sim = std::make_unique<Simulator>(b.build(p));
    s = rest_state(b);
  }
  ModelBuilder b;
  std::unique_ptr<Simulator> sim;
  State s;
};

TEST(ConstraintGroups, TwoClampsBalanceTheWeightAndEachOther) {
  TwoClamps t;
  Simulator& sim = *t.sim;
  for (int i = 0; i < 30000; ++i) ASSERT_TRUE(sim.step(t.s).ok()) << i;  // 3 s
  Eigen::Vector3d fl = Eigen::Vector3d::Zero(), fr = fl;
  for (int i = 0; i < 200; ++i) {
    ASSERT_TRUE(sim.step(t.s).ok());
    fl += sim.data().constraint("left")->force / 200;
    fr += sim.data().constraint("right")->force / 200;
  }
  const double weight = sim.model().mass.sum() * 981;
  // together they carry the weight
  EXPECT_NEAR(fl.z() + fr.z(), weight, 0.01 * weight);
  // and pull against each other along the yarn: equal and opposite across
  EXPECT_GT(std::abs(fl.x()), 0.05 * weight) << "a sagging yarn is under tension";
  EXPECT_NEAR(fl.x() + fr.x(), 0.0, 0.01 * weight);
  EXPECT_NEAR(fl.y() + fr.y(), 0.0, 0.01 * weight);
  for (const char* name : {"left", "right"}) {
    const ConstraintRecord& c = *sim.data().constraint(name);
    EXPECT_EQ(c.kind, "clamp");
    EXPECT_EQ(c.rows, 9);
    EXPECT_LT(c.max_violation, 1e-6);
  }
}

// Newton's second law for the whole yarn, step by step: with no global damping every
// other force is internal (bending, length, length constraints, contact between its own
// segments), so the momentum changes by h · (M g + Σ clamp forces) exactly (the explicit
// step's internal forces cancel to round-off). One clamp holds still, the other drags and
// turns its end about.
TEST(ConstraintGroups, MomentumChangesByTheExternalForces) {
  Keyframe k0, k1, k2;
  k1.time = 0.05;
  k1.translation = Eigen::Vector3d(-1.0, 0.5, 0.8);
  k2.time = 0.1;
  k2.translation = Eigen::Vector3d(-0.5, -0.5, 2.0);
  k2.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ()));
  TwoClamps t({k0, k1, k2}, 0.0);
  Simulator& sim = *t.sim;
  const Model& m = sim.model();
  const double h = m.params.solver.time_step;
  const Eigen::Vector3d weight = m.mass.sum() * m.params.gravity;
  double worst = 0, scale = 0;
  for (int i = 0; i < 1500; ++i) {  // 0.15 s: accelerating, turning, then held
    const Eigen::Vector3d p0 = sim.linear_momentum(t.s);
    ASSERT_TRUE(sim.step(t.s).ok()) << i;
    const Eigen::Vector3d dp = sim.linear_momentum(t.s) - p0;
    const Eigen::Vector3d f =
        weight + sim.data().constraint("left")->force + sim.data().constraint("right")->force;
    worst = std::max(worst, (dp / h - f).norm());
    scale = std::max(scale, f.norm());
  }
  ASSERT_GT(scale, 2 * weight.norm()) << "the moving clamp should dominate";
  EXPECT_LT(worst, 1e-9 * scale) << "largest |Δp/h − ΣF| against max |ΣF| = " << scale;
}

TEST(ConstraintGroups, ClampFollowsItsKeyframes) {
  Keyframe k0, k1;
  k1.time = 0.05;
  k1.translation = Eigen::Vector3d(0, 0, 1);
  k1.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()));
  TwoClamps t({k0, k1}, 0.5);
  Simulator& sim = *t.sim;
  const Clamp& right = sim.model().clamps[1];
  for (int i = 0; i < 800; ++i) ASSERT_TRUE(sim.step(t.s).ok()) << i;  // past the last keyframe
  // interpolation ends on the last keyframe: each held point is at its moved place
  for (size_t k = 0; k < right.points.size(); ++k) {
    const Eigen::Vector3d want =
        right.centre + k1.translation + k1.rotation * (right.rest[k] - right.centre);
    EXPECT_LT((point_position(sim.model(), t.s.q, right.points[k]) - want).norm(), 1e-6) << k;
  }
  // halfway: half the translation, half the angle
  const Keyframe mid = right.pose(0.025);
  EXPECT_NEAR((mid.translation - 0.5 * k1.translation).norm(), 0.0, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(mid.rotation).angle(), 0.15, 1e-12);
}

TEST(ConstraintGroups, ModelListsItsGroupsInOrder) {
  ModelBuilder b;
  b.add_yarn(line({0, 0, 0}, {4, 0, 0}, 8));
  b.add_pin({{0, 0.0}, Eigen::Vector3d::Zero()});
  b.add_glue({{1, 0.5}, {6, 0.5}});
  Clamp c;
  c.points = {{7, 1.0}};
  b.add_clamp(c);
  const Model m = with_constraint_groups(b.build(Params{}));
  ASSERT_EQ(m.constraint_groups.size(), 4u);
  const char* names[] = {"length", "pin0", "glue0", "clamp0"};
  for (int k = 0; k < 4; ++k) EXPECT_EQ(m.constraint_groups[k]->name(), names[k]);
  Clamp empty;
  ModelBuilder b2 = b;
  b2.add_clamp(empty);
  EXPECT_THROW(b2.build(Params{}), std::invalid_argument);
}

}  // namespace
}  // namespace knit

namespace knit {
namespace {

// A yarn hanging between two clamps that each hold one end point settles into a catenary
// y = a cosh(x/a): with span S and length L, L = 2a sinh(S / 2a); each clamp carries half
// the weight, μ g L / 2, vertically, and the horizontal tension μ g a. Bending is made
// negligible (k_bend = 0.005 g cm³/s²: the bending length √(k_bend / μg) ≈ 0.03 cm against
// a 12 cm yarn).
TEST(ConstraintGroups, ClampsOfAHangingYarnCarryTheCatenarysForces) {
  const double span = 8;
  Eigen::Matrix3Xd cp(3, 27);  // 24 segments, laid in a sag of about the right depth
  for (int k = 0; k < 27; ++k) {
    const double x = span * (k - 1) / 24.0;
    cp.col(k) = Eigen::Vector3d(x, 0, -0.09 * x * (span - x));
  }
  ModelBuilder b;
  b.add_yarn(cp);
  Clamp left, right;
  left.points = {{0, 0.0}};
  right.points = {{23, 1.0}};
  b.add_clamp(left);
  b.add_clamp(right);
  Params p;
  p.material.k_bend = 0.005;
  p.material.k_global = 0.05;
  p.material.contact = false;
  p.solver.time_step = 1e-4;
  Simulator sim(b.build(p));
  State s = rest_state(b);
  for (int i = 0; i < 40000; ++i) ASSERT_TRUE(sim.step(s).ok()) << i;  // 4 s
  const Model& m = sim.model();
  const double length = m.total_length();
  const double S =
      (point_position(m, s.q, right.points[0]) - point_position(m, s.q, left.points[0])).norm();
  // L = 2a sinh(S/2a) by bisection on a
  double lo = 0.1, hi = 1000;
  for (int it = 0; it < 200; ++it) {
    const double a = 0.5 * (lo + hi);
    (2 * a * std::sinh(S / (2 * a)) > length ? lo : hi) = a;
  }
  const double a = 0.5 * (lo + hi);
  const double mu_g = p.material.density * 981;
  Eigen::Vector3d fl = Eigen::Vector3d::Zero(), fr = fl;
  for (int i = 0; i < 500; ++i) {
    ASSERT_TRUE(sim.step(s).ok());
    fl += sim.data().constraint("clamp0")->force / 500;
    fr += sim.data().constraint("clamp1")->force / 500;
  }
  const double weight = mu_g * length;
  EXPECT_NEAR(fl.z(), weight / 2, 0.02 * weight / 2);
  EXPECT_NEAR(fr.z(), weight / 2, 0.02 * weight / 2);
  EXPECT_NEAR(-fl.x(), mu_g * a, 0.02 * mu_g * a) << "a = " << a << " cm";
  EXPECT_NEAR(fr.x(), mu_g * a, 0.02 * mu_g * a);
}

}  // namespace
}  // namespace knit
