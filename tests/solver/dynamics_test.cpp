// Physical checks of the time step: conservation laws, energy behaviour, rest states.
#include <gtest/gtest.h>

#include "fd_check.hpp"
#include "knit/energy/bending.hpp"
#include "knit/energy/length.hpp"
#include "knit/solver/simulator.hpp"

namespace knit {
namespace {

Eigen::Matrix3Xd line(int segments, double length) {
  Eigen::Matrix3Xd cp(3, segments + 3);
  for (int k = 0; k < segments + 3; ++k)
    cp.col(k) = Eigen::Vector3d((k - 1) * length / segments, 0, 0);
  return cp;
}

// Zero gravity, no pins, a spinning and drifting bent yarn: no external force or torque,
// so linear and angular momentum are conserved (internal forces are translation- and
// rotation-invariant; the projection is internal too).
TEST(Dynamics, FreeYarnConservesMomentum) {
  Eigen::Matrix3Xd cp(3, 24);
  for (int k = 0; k < 24; ++k)
    cp.col(k) = Eigen::Vector3d(2 * std::cos(0.25 * k), 2 * std::sin(0.25 * k), 0.05 * k);
  ModelBuilder b;
  b.add_yarn(cp);
  Params p;
  p.gravity.setZero();
  Simulator sim(b.build(p));
  State s;
  s.q = b.positions();
  s.v.resize(s.q.size());
  for (int k = 0; k < sim.model().num_cp(); ++k)  // spin about z plus a drift, plus noise
    s.v.segment<3>(3 * k) =
        Eigen::Vector3d(-s.q[3 * k + 1], s.q[3 * k], 0) * 3.0 + Eigen::Vector3d(1, 2, 0.5);
  s.v = test::jitter(s.v, 0.5, 3);
  const Eigen::Vector3d p0 = sim.linear_momentum(s), l0 = sim.angular_momentum(s);
  // the explicit midpoint step conserves linear momentum exactly and angular momentum to
  // O(h²) per step; projection is internal. Check both, and that halving h shrinks the
  // angular drift.
  auto run = [&](double h) {
    Simulator sim2(sim.model());
    State st = s;
    for (int i = 0; i < std::lround(0.2 / h); ++i)
      EXPECT_TRUE(sim2.step(st, h).ok()) << "step " << i;
    EXPECT_LT((sim2.linear_momentum(st) - p0).norm(), 1e-9 * (1 + p0.norm()))
        << "linear momentum drifted, h = " << h;
    return (sim2.angular_momentum(st) - l0).norm() / l0.norm();
  };
  const double drift = run(1e-4), finer = run(5e-5);
  EXPECT_LT(drift, 1e-2) << "relative angular momentum drift";
  EXPECT_LT(finer, drift) << "angular momentum drift must shrink with h";
}

// An undamped pendulum: a 10 cm yarn pinned at one end, released horizontally. The
// integrator (explicit midpoint + projection with velocity correction) is dissipative at
// first order in h; over 1 s the total energy may fall but must stay within 15 % of the
// energy scale m g L, must never rise, and the loss must shrink as h is halved.
double pendulum_energy_drift(double h, double duration) {
  ModelBuilder b;
  b.add_yarn(line(20, 10.0));
  b.add_pin({{0, 0.0}, Eigen::Vector3d::Zero()});
  Simulator sim(b.build(Params{}));
  State s;
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  const double e0 = sim.kinetic_energy(s) + sim.potential_energy(s);
  double max_rise = 0;
  const int steps = static_cast<int>(std::lround(duration / h));
  for (int i = 0; i < steps; ++i) {
    EXPECT_TRUE(sim.step(s, h).ok());
    if (i % 100 == 0)
      max_rise = std::max(max_rise, sim.kinetic_energy(s) + sim.potential_energy(s) - e0);
  }
  const double mgl = sim.model().mass.sum() * 981 * 10.0;
  EXPECT_LT(max_rise, 0.01 * mgl) << "energy must not grow";
  return (sim.kinetic_energy(s) + sim.potential_energy(s) - e0) / mgl;
}

TEST(Dynamics, UndampedPendulumEnergyStaysWithinBound) {
  const double drift = pendulum_energy_drift(1e-4, 1.0);
  EXPECT_LT(std::abs(drift), 0.15) << "relative energy drift " << drift;
  const double finer = pendulum_energy_drift(5e-5, 1.0);
  EXPECT_LT(std::abs(finer), std::abs(drift)) << "drift must shrink with h";
}

// A yarn hanging from two pins with a little global damping comes to rest with its
// lengths held. "At rest" is judged on positions: under a constant load the velocity
// correction of the projection (v += Δq/h after a midpoint step) leaves a steady O(h)
// velocity residual although nothing moves; check that it shrinks with h.
struct HangResult {
  double max_drift_cm;    // largest control-point displacement over the last 0.2 s
  double residual_speed;  // rms velocity at the end (cm/s)
};

HangResult hang(double h) {
  ModelBuilder b;
  Eigen::Matrix3Xd cp(3, 19);
  for (int k = 0; k < 19; ++k)
    cp.col(k) = Eigen::Vector3d((k - 1) * 0.5, 0, -0.08 * (k - 1) * (15 - k));
  b.add_yarn(cp);
  b.add_pin({{0, 0.0}, Eigen::Vector3d::Zero()});
  b.add_pin({{15, 1.0}, Eigen::Vector3d::Zero()});
  Params p;
  p.material.k_global = 0.02;
  Model m = b.build(p);
  m.pins[0].origin = point_position(m, b.positions(), {0, 0.0});
  m.pins[1].origin = point_position(m, b.positions(), {15, 1.0});
  build_constraint_groups(m);  // the groups hold copies of the pins
  Simulator sim(m);
  State s;
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  const int steps = static_cast<int>(std::lround(3.0 / h)),
            tail = static_cast<int>(std::lround(0.2 / h));
  Eigen::VectorXd q_before;
  for (int i = 0; i < steps; ++i) {
    if (i == steps - tail) q_before = s.q;
    EXPECT_TRUE(sim.step(s, h).ok()) << "step " << i;
  }
  EXPECT_LT(FastProjection::max_length_violation(sim.model(), s.q),
            m.params.solver.constraint_tolerance);
  EXPECT_LT(sim.max_violation(s), m.params.solver.constraint_tolerance);
  const double drift = (s.q - q_before).reshaped(3, m.num_cp()).colwise().norm().maxCoeff();
  return {drift, std::sqrt(2 * sim.kinetic_energy(s) / m.mass.sum())};
}

TEST(Dynamics, HangingYarnComesToRest) {
  const HangResult coarse = hang(1e-4), fine = hang(5e-5);
  EXPECT_LT(coarse.max_drift_cm, 1e-3) << "still moving (cm over 0.2 s)";
  EXPECT_LT(fine.max_drift_cm, 1e-3) << "still moving (cm over 0.2 s)";
  EXPECT_LT(coarse.residual_speed, 981 * 1e-4 * 3) << "velocity residual should be O(h g)";
  EXPECT_LT(fine.residual_speed, 0.7 * coarse.residual_speed) << "residual must shrink with h";
}

// A step that blows up leaves the state untouched and says so.
TEST(Dynamics, UnstableStepKeepsLastGoodState) {
  ModelBuilder b;
  b.add_yarn(line(10, 5.0));
  Params p;
  p.material.k_len = 1e9;  // absurdly stiff: explicit step explodes
  Model m = b.build(p, 0.5);
  Simulator sim(m);
  State s;
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  StepResult r;
  State last = s;
  for (int i = 0; i < 200 && r.ok(); ++i) {
    last = s;
    r = sim.step(s, 1e-2);
  }
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.message.find("smaller time step"), std::string::npos) << r.message;
  EXPECT_TRUE(s.finite());
  EXPECT_EQ(s.q, last.q);
  EXPECT_EQ(s.time, last.time);
}

}  // namespace
}  // namespace knit
