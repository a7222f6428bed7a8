// Physical checks of the time step: conservation laws, energy behaviour, rest states.
#include <gtest/gtest.h>

#include <limits>
#include <numbers>

#include "fd_check.hpp"
#include "knit/energy/bending.hpp"
#include "knit/energy/length.hpp"
#include "knit/solver/simulator.hpp"
#include "yarn_setups.hpp"

namespace knit {
namespace {

using test::line;
using test::pendulum_energy_drift;

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

// Free fall (MODEL.md §2 with gravity the only external force). The explicit midpoint step
// is exact for a constant acceleration: q_{n+1} = q_n + h v_n + ½ h² g, v_{n+1} = v_n + h g,
// so after n steps q = q_0 + ½ g t², v = g t with t = n h. A straight yarn at its rest
// length has no bending, length or contact force and its length constraints hold exactly
// (the projection moves nothing), so every control point must fall at exactly g.
TEST(Dynamics, StraightYarnFallsAtExactlyG) {
  ModelBuilder b;
  Eigen::Matrix3Xd cp = line(12, 6.0);
  cp.row(1).setLinSpaced(0.0, 1.5);  // oblique to gravity's axis, still straight
  b.add_yarn(cp);
  const Model m = b.build(Params{});
  const Eigen::Vector3d g = m.params.gravity;
  ASSERT_EQ(g, Eigen::Vector3d(0, 0, -981));
  Simulator sim(m);
  State s;
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  const Eigen::VectorXd q0 = s.q;
  const double h = 1e-4;
  for (int n = 1; n <= 500; ++n) {  // 0.05 s, 1.23 cm
    ASSERT_TRUE(sim.step(s, h).ok()) << "step " << n;
    const double t = n * h;
    for (int k = 0; k < m.num_cp(); ++k) {
      ASSERT_LT((s.q.segment<3>(3 * k) - q0.segment<3>(3 * k) - 0.5 * g * t * t).norm(), 1e-10)
          << "control point " << k << ", step " << n;
      ASSERT_LT((s.v.segment<3>(3 * k) - g * t).norm(), 1e-9) << "control point " << k;
    }
  }
}

// A coiled yarn pressed into contact with itself (turns 0.88 · 2r apart) falls while its
// bending, length and contact forces and the length projection act inside it: they are
// internal (they sum to zero), so its centre of mass still falls at exactly g.
TEST(Dynamics, CentreOfMassOfACoiledYarnFallsAtExactlyG) {
  const int segments = 60;
  const double turn = 2 * std::numbers::pi / 16;      // 16 segments per turn
  const double pitch = 0.88 * 2 * Material{}.radius;  // cm per turn: d = 0.88
  Eigen::Matrix3Xd cp(3, segments + 3);
  for (int k = 0; k < segments + 3; ++k)  // axis along x, across gravity
    cp.col(k) = Eigen::Vector3d(pitch * k * turn / (2 * std::numbers::pi), std::cos(k * turn),
                                std::sin(k * turn));
  ModelBuilder b;
  b.add_yarn(cp);
  Simulator sim(b.build(Params{}));
  const Model& m = sim.model();
  State s;
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  const Eigen::VectorXd q0 = s.q;
  const double mass = m.mass.sum();
  auto centre = [&](const State& st) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < m.num_cp(); ++k) c += m.mass[k] * st.q.segment<3>(3 * k);
    return Eigen::Vector3d(c / mass);
  };
  const Eigen::Vector3d c0 = centre(s), g = m.params.gravity;
  const double h = 1e-4;
  double contact_energy = 0, deformation = 0;
  for (int n = 1; n <= 500; ++n) {
    ASSERT_TRUE(sim.step(s, h).ok()) << "step " << n;
    const double t = n * h;
    ASSERT_LT((centre(s) - c0 - 0.5 * g * t * t).norm(), 1e-10) << "step " << n;
    ASSERT_LT((sim.linear_momentum(s) - mass * g * t).norm(), 1e-9 * mass) << "step " << n;
    for (const TermRecord& rec : sim.data().terms)
      if (rec.name == "contact") contact_energy = std::max(contact_energy, rec.energy);
    for (int k = 0; k < m.num_cp(); ++k)
      deformation = std::max(
          deformation, (s.q.segment<3>(3 * k) - q0.segment<3>(3 * k) - 0.5 * g * t * t).norm());
  }
  // the forces inside did act: the turns touched, and the coil (bent to a 1 cm radius, its
  // ends free) springs open as it falls (measured: a control point 6 cm off the rigid fall
  // after 0.05 s)
  EXPECT_GT(contact_energy, 0) << "the turns never touched: the test would not test contact";
  EXPECT_GT(deformation, 1.0) << "cm: the coil fell as a rigid body";
}

// Global damping (MODEL.md §4): D_i = k_global ∫ v_iᵀ v_i dt, lumped like the mass, gives
// control point k of a yarn of equal segments ℓ the force −λ m_k v_k with
// λ = 2 k_global / (μ ℓ) (m_k = μ ℓ Σ∫B, the damping weight k_global Σ∫B). A freely
// translating straight yarn feels nothing else, so v' = −λ v: v = v_0 exp(−λt),
// x − x_0 = v_0 (1 − exp(−λt)) / λ. The explicit midpoint step does this exactly as
// v_{n+1} = ρ v_n with ρ = 1 − λh + (λh)²/2, x_{n+1} = x_n + h (1 − λh/2) v_n.
// With λ = 100/s and h = 1e-4 s, ρⁿ differs from exp(−λnh) by ≈ n (λh)³/6 = 5e-5
// (relative) after n = 300 steps; allowed 1e-4. The step itself must match ρⁿ to rounding
// (1e-10).
TEST(Dynamics, GlobalDampingDecaysATranslatingYarnExponentially) {
  const int segments = 10;
  const double ell = 0.5;
  ModelBuilder b;
  b.add_yarn(line(segments, segments * ell));
  Params p;
  p.gravity.setZero();
  p.material.k_global = 0.15;
  const Model m = b.build(p);
  const double lambda = 2 * p.material.k_global / (p.material.density * ell);  // 1/s
  ASSERT_NEAR(lambda, 100.0, 1e-9);
  Simulator sim(m);
  State s;
  s.q = b.positions();
  s.v.resize(s.q.size());
  const Eigen::Vector3d v0(3, -1, 2);
  for (int k = 0; k < m.num_cp(); ++k) s.v.segment<3>(3 * k) = v0;
  const Eigen::VectorXd q0 = s.q;
  const double h = 1e-4, rho = 1 - lambda * h + 0.5 * std::pow(lambda * h, 2);
  for (int n = 1; n <= 300; ++n) {
    ASSERT_TRUE(sim.step(s, h).ok()) << "step " << n;
    const double t = n * h, discrete = std::pow(rho, n), exact = std::exp(-lambda * t);
    const double travel_discrete = h * (1 - 0.5 * lambda * h) * (1 - discrete) / (1 - rho);
    const double travel_exact = (1 - exact) / lambda;
    for (int k = 0; k < m.num_cp(); ++k) {
      const Eigen::Vector3d v = s.v.segment<3>(3 * k);
      const Eigen::Vector3d dx = s.q.segment<3>(3 * k) - q0.segment<3>(3 * k);
      ASSERT_LT((v - discrete * v0).norm(), 1e-10 * v0.norm()) << "cp " << k << ", step " << n;
      ASSERT_LT((v - exact * v0).norm(), 1e-4 * exact * v0.norm()) << "cp " << k << ", step " << n;
      ASSERT_LT((dx - travel_discrete * v0).norm(), 1e-10 * travel_discrete * v0.norm())
          << "cp " << k << ", step " << n;
      ASSERT_LT((dx - travel_exact * v0).norm(), 1e-4 * travel_exact * v0.norm())
          << "cp " << k << ", step " << n;
    }
  }
}

// An undamped pendulum: a 10 cm yarn pinned at one end, released horizontally. The
// integrator (explicit midpoint + projection with velocity correction) is dissipative at
// first order in h: over 1 s the total energy falls, and must never rise (checked at
// every step), and the loss must shrink as h is halved. Measured: loss 5.95 % of m g L
// at h = 1e-4 s, 3.63 % at 5e-5 s (ratio 0.61); the energy exceeds its start by at most
// 5e-9 m g L (rounding, in the first steps). Allowed: loss ≤ 7 % (+1 point), rise
// ≤ 1e-6 m g L, ratio ≤ 0.75.
TEST(Dynamics, UndampedPendulumEnergyStaysWithinBound) {
  const double drift = pendulum_energy_drift(1e-4, 1.0);
  EXPECT_LT(drift, 0.0) << "the midpoint step with projection dissipates";
  EXPECT_GT(drift, -0.07) << "relative energy drift " << drift;
  const double finer = pendulum_energy_drift(5e-5, 1.0);
  EXPECT_LT(std::abs(finer), 0.75 * std::abs(drift)) << "drift must shrink with h";
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
  Params p;
  p.material.k_global = 0.02;
  State s;
  const Model m = test::hanging_yarn(p, s.q);
  Simulator sim(m);
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
