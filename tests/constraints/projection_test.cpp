#include "knit/constraints/projection.hpp"

#include <gtest/gtest.h>

#include "fd_check.hpp"
#include "knit/constraints/inextensibility.hpp"

namespace knit {
namespace {

Eigen::Matrix3Xd wavy(int n, double phase = 0) {
  Eigen::Matrix3Xd cp(3, n);
  for (int k = 0; k < n; ++k)
    cp.col(k) = Eigen::Vector3d(0.3 * k, 0.25 * std::sin(0.8 * k + phase), 0.1 * std::cos(1.1 * k));
  return cp;
}

TEST(Inextensibility, GradientMatchesFiniteDifferences) {
  const QuadratureTable q = simpson_table(11);
  const Eigen::Matrix3Xd cp = wavy(4);
  Vector12d x;
  for (int a = 0; a < 4; ++a) x.segment<3>(3 * a) = cp.col(a);
  const double rest = 1.1 * segment_arclength(x, q);
  Vector12d g;
  length_constraint(x, rest, q, &g);
  test::expect_gradient_matches(
      [&](const Eigen::VectorXd& y) { return length_constraint(Vector12d(y), rest, q, nullptr); },
      x, g, 1e-7, 1e-7, "length constraint");
  EXPECT_NEAR(length_constraint(x, segment_arclength(x, q), q, nullptr), 0.0, 1e-15);
}

TEST(Projection, ConvergesFromPerturbedStateWithinFiveIterations) {
  ModelBuilder b;
  b.add_yarn(wavy(30));
  b.add_yarn(wavy(20, 1.0).colwise() + Eigen::Vector3d(0, 2, 0));
  b.add_pin({{0, 0.0}, Eigen::Vector3d::Zero()});
  Model m = b.build(Params{});
  m.pins[0].origin = point_position(m, b.positions(), m.pins[0].at);
  FastProjection proj(m);
  Eigen::VectorXd q = test::jitter(b.positions(), 0.03, 17);
  ASSERT_GT(proj.max_violation(m, q, 0.0), 1e-2);
  const ProjectionResult r = proj.project(m, q, 0.0);
  EXPECT_TRUE(r.converged);
  EXPECT_LE(r.iterations, 5);
  EXPECT_LT(proj.max_violation(m, q, 0.0), m.params.constraint_tolerance);
}

// Inextensibility constraints are internal: their gradients sum to zero over a yarn's
// coordinates per axis (translation invariance), so with lumped mass the projection
// Δq = −M⁻¹Gᵀδλ leaves Σ m_k Δq_k = 0: the centre of mass (hence momentum) is unchanged.
TEST(Projection, PreservesCentreOfMassWithoutPins) {
  ModelBuilder b;
  b.add_yarn(wavy(25));
  const Model m = b.build(Params{});
  FastProjection proj(m);
  Eigen::VectorXd q = test::jitter(b.positions(), 0.03, 21);
  auto com = [&](const Eigen::VectorXd& x) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < m.num_cp(); ++k) c += m.mass[k] * x.segment<3>(3 * k);
    return c;
  };
  const Eigen::Vector3d before = com(q);
  const ProjectionResult r = proj.project(m, q, 0.0);
  ASSERT_TRUE(r.converged);
  ASSERT_GE(r.iterations, 1);
  EXPECT_LT((com(q) - before).norm(), 1e-12);
}

TEST(Projection, GlueAndMovingPinAreSatisfied) {
  ModelBuilder b;
  b.add_yarn(wavy(20));
  b.add_yarn(wavy(20).colwise() + Eigen::Vector3d(0, 0, 0.1));  // 17 segments, 0.1 cm above
  Pin pin;
  pin.at = {0, 0.0};
  pin.velocity = Eigen::Vector3d(1, 0, 0);
  b.add_pin(pin);
  b.add_glue({{17 + 10, 0.5}, {10, 0.5}});  // yarn 1 segment 10 onto yarn 0 segment 10
  Model m = b.build(Params{});
  m.pins[0].origin = point_position(m, b.positions(), {0, 0.0});
  FastProjection proj(m);
  Eigen::VectorXd q = b.positions();
  const ProjectionResult r = proj.project(m, q, 0.05);  // pin target moved 0.05 cm
  ASSERT_TRUE(r.converged) << r.max_violation;
  EXPECT_LT((point_position(m, q, {0, 0.0}) - m.pins[0].target(0.05)).norm(), 1e-6);
  EXPECT_LT((point_position(m, q, {27, 0.5}) - point_position(m, q, {10, 0.5})).norm(), 1e-6);
}

}  // namespace
}  // namespace knit
