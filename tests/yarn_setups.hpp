#pragma once
// Small yarn set-ups shared by the dynamics tests (gtest: some check as they run).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "knit/constraints/groups.hpp"
#include "knit/model/model.hpp"
#include "knit/solver/simulator.hpp"

namespace knit::test {

/// Control points of a straight yarn of `segments` segments along x from 0 to `length` cm.
inline Eigen::Matrix3Xd line(int segments, double length) {
  Eigen::Matrix3Xd cp(3, segments + 3);
  for (int k = 0; k < segments + 3; ++k)
    cp.col(k) = Eigen::Vector3d((k - 1) * length / segments, 0, 0);
  return cp;
}

/// A yarn of 16 segments, 0.5 cm of control-point spacing, sagging in a parabola and
/// pinned at both ends where it starts (its positions in q0).
inline Model hanging_yarn(const Params& p, Eigen::VectorXd& q0) {
  ModelBuilder b;
  Eigen::Matrix3Xd cp(3, 19);
  for (int k = 0; k < 19; ++k)
    cp.col(k) = Eigen::Vector3d((k - 1) * 0.5, 0, -0.08 * (k - 1) * (15 - k));
  b.add_yarn(cp);
  b.add_pin({{0, 0.0}, Eigen::Vector3d::Zero()});
  b.add_pin({{15, 1.0}, Eigen::Vector3d::Zero()});
  Model m = b.build(p);
  m.pins[0].origin = point_position(m, b.positions(), {0, 0.0});
  m.pins[1].origin = point_position(m, b.positions(), {15, 1.0});
  build_constraint_groups(m);  // the groups hold copies of the pins
  q0 = b.positions();
  return m;
}

/// An undamped pendulum: a 10 cm yarn of 20 segments pinned at one end, released
/// horizontally, stepped for `duration` s at h. Fails the calling test where the total
/// energy rises above its start by more than 1e-6 m g L at any step; returns the relative
/// change of the total energy at the end, (E − E0) / (m g L).
inline double pendulum_energy_drift(double h, double duration,
                                    Integrator integrator = Integrator::EXPLICIT) {
  ModelBuilder b;
  b.add_yarn(line(20, 10.0));
  b.add_pin({{0, 0.0}, Eigen::Vector3d::Zero()});
  Params p;
  p.solver.integrator = integrator;
  Simulator sim(b.build(p));
  State s;
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  const double e0 = sim.kinetic_energy(s) + sim.potential_energy(s);
  const double mgl = sim.model().mass.sum() * 981 * 10.0;
  double max_rise = -std::numeric_limits<double>::infinity();
  const int steps = static_cast<int>(std::lround(duration / h));
  for (int i = 0; i < steps; ++i) {
    EXPECT_TRUE(sim.step(s, h).ok());
    // the step's own record: kinetic and potential energy at its result
    const double e = sim.data().kinetic_energy + sim.data().potential_energy;
    max_rise = std::max(max_rise, e - e0);
  }
  EXPECT_LT(max_rise, 1e-6 * mgl) << "energy must not grow (h = " << h << ")";
  return (sim.kinetic_energy(s) + sim.potential_energy(s) - e0) / mgl;
}

}  // namespace knit::test
