// A yarn hanging under gravity between two points a span S apart settles into a
// catenary y = a cosh(x/a): its length L = 2a sinh(S / 2a) fixes a, and each support then
// carries the horizontal tension H = μ g a and half the weight, V = μ g L / 2. The yarn
// is the simulation preset's (inextensible by projection, μ = 0.006 g/cm) with a soft
// bending stiffness, k_bend = 0.005 g cm³/s² (the relaxation preset's): its boundary layer
// at the supports is √(k_bend / H) ≈ 0.01 cm against a 20 cm yarn, so bending changes
// the support forces by far less than the 2 % allowed. (With the simulation preset's
// k_bend = 5 the layer is 0.3 cm.) The forces are the pins' constraint records — what the
// supports exert, as a stretch test reads its clamps — averaged over the last 0.1 s.
// Measured: H and V within 0.4 % of the catenary's on both sags. The static reactions at
// the last state (StepData::static_constraints, what a quasi-static stretch test reads:
// no inertia, no damping) match them as well.
#include <gtest/gtest.h>

#include <cmath>

#include "knit/constraints/groups.hpp"
#include "knit/solver/simulator.hpp"

namespace knit {
namespace {

// a with 2a sinh(S / 2a) = L (L > S), by bisection on the monotone function
double catenary_parameter(double span, double length) {
  double lo = 1e-3 * span, hi = 1e3 * span;
  for (int i = 0; i < 200; ++i) {
    const double a = std::sqrt(lo * hi);
    (2 * a * std::sinh(span / (2 * a)) > length ? lo : hi) = a;
  }
  return std::sqrt(lo * hi);
}

struct Support {
  Eigen::Vector3d left, right;                // mean force each pin exerts on the yarn (dyn)
  Eigen::Vector3d static_left, static_right;  // the pins' static reactions at the end (dyn)
  double residual = 0;                        // the force residual there (cm/s²)
  double span = 0, length = 0, weight = 0;
};

Support hang_catenary(double sag_parameter) {
  // control points on a catenary of roughly the final shape (the B-spline's curve lies a
  // little inside them: the model's own rest lengths and end points are what count)
  const double span = 16, a0 = sag_parameter;
  const int segments = 40;
  Eigen::Matrix3Xd cp(3, segments + 3);
  for (int k = 0; k < segments + 3; ++k) {
    const double x = (k - 1) * span / segments;
    cp.col(k) = Eigen::Vector3d(x, 0, a0 * std::cosh((x - 0.5 * span) / a0));
  }
  ModelBuilder b;
  b.add_yarn(cp);
  b.add_pin({{0, 0.0}, Eigen::Vector3d::Zero()});
  b.add_pin({{segments - 1, 1.0}, Eigen::Vector3d::Zero()});
  Params p = Params::simulation();
  p.material.k_bend = 0.005;
  p.material.contact = false;
  p.material.k_global = 0.05;  // settles the swinging; exerts nothing at rest
  Model m = b.build(p);
  m.pins[0].origin = point_position(m, b.positions(), {0, 0.0});
  m.pins[1].origin = point_position(m, b.positions(), {segments - 1, 1.0});
  build_constraint_groups(m);
  Support out;
  out.span = (m.pins[1].origin - m.pins[0].origin).norm();
  for (double l : m.rest_length) out.length += l;
  out.weight = m.mass.sum() * 981;

  Simulator sim(m);
  State s;
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  // 4 s at h = 2e-4 s: the supports are within 0.8 % of the catenary's (0.4 % at 1e-4 s,
  // twice the steps)
  const double h = 2e-4;
  const int steps = 20000, tail = 500;
  out.left.setZero();
  out.right.setZero();
  for (int i = 0; i < steps; ++i) {
    EXPECT_TRUE(sim.step(s, h).ok()) << "step " << i;
    if (i >= steps - tail) {
      out.left += sim.data().constraint("pin0")->force / tail;
      out.right += sim.data().constraint("pin1")->force / tail;
    }
  }
  out.residual = sim.force_residual(s);
  out.static_left = sim.data().static_constraint("pin0")->force;
  out.static_right = sim.data().static_constraint("pin1")->force;
  return out;
}

TEST(Catenary, SupportForcesMatchTheCatenary) {
  // a deep sag (L/S ≈ 1.25) and a shallow one (L/S ≈ 1.05)
  for (const double a0 : {6.0, 14.0}) {
    const Support r = hang_catenary(a0);
    const double mu = 0.006, g = 981;
    ASSERT_GT(r.length, r.span * 1.01);
    const double a = catenary_parameter(r.span, r.length);
    const double H = mu * g * a, V = 0.5 * mu * g * r.length;
    SCOPED_TRACE("span " + std::to_string(r.span) + " cm, length " + std::to_string(r.length) +
                 " cm, a = " + std::to_string(a) + " cm");
    // the weight the model carries is the uniform yarn's μ g L
    EXPECT_NEAR(r.weight, mu * g * r.length, 0.005 * mu * g * r.length);
    // left support pulls towards −x, right towards +x; both hold half the weight up
    EXPECT_NEAR(-r.left.x(), H, 0.02 * H);
    EXPECT_NEAR(r.right.x(), H, 0.02 * H);
    EXPECT_NEAR(r.left.z(), V, 0.02 * V);
    EXPECT_NEAR(r.right.z(), V, 0.02 * V);
    EXPECT_LT(std::abs(r.left.y()) + std::abs(r.right.y()), 1e-6 * V);
    // at rest (the residual a small part of g), the static reactions carry the same loads
    EXPECT_LT(r.residual, 0.05 * g);
    EXPECT_NEAR(-r.static_left.x(), H, 0.02 * H);
    EXPECT_NEAR(r.static_right.x(), H, 0.02 * H);
    EXPECT_NEAR(r.static_left.z(), V, 0.02 * V);
    EXPECT_NEAR(r.static_right.z(), V, 0.02 * V);
  }
}

}  // namespace
}  // namespace knit
