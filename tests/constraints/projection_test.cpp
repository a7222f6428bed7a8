// the dense oracle below uses Eigen's dense product and LDLT, inside which GCC 12 warns
// falsely (-Wmaybe-uninitialized in its AVX-512 intrinsics)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "knit/constraints/projection.hpp"
#include "knit/constraints/groups.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "fd_check.hpp"
#include "knit/constraints/inextensibility.hpp"

#include <Eigen/Dense>

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

// length_constraints takes four segments at a time, one per SIMD lane: each lane must give
// what the one-segment formula gives (the same operations; only the compiler's fused
// multiply-adds may round differently), for every segment, a listed subset, and a last
// partial group of lanes.
TEST(Inextensibility, LanesMatchTheOneSegmentFormula) {
  ModelBuilder b;
  b.add_yarn(wavy(31));
  b.add_yarn(wavy(20, 1.0).colwise() + Eigen::Vector3d(0, 2, 0));
  const Model m = b.build(Params{});
  const Eigen::VectorXd q = test::jitter(b.positions(), 0.05, 3);
  for (const std::vector<int>& segments : {std::vector<int>{}, std::vector<int>{4, 0, 31, 7, 19}}) {
    const int rows = segments.empty() ? m.num_seg() : static_cast<int>(segments.size());
    ASSERT_NE(rows % 4, 0) << "a partial group of lanes is part of the test";
    std::vector<double> c(rows), grad(12 * rows), c_only(rows);
    length_constraints(m, q, segments, rows, c.data(), grad.data());
    length_constraints(m, q, segments, rows, c_only.data(), nullptr);
    for (int row = 0; row < rows; ++row) {
      const int i = segments.empty() ? row : segments[row];
      Vector12d g;
      const double want =
          length_constraint(gather_segment(q, m.seg_cp[i]), m.rest_length[i], m.quad, &g);
      EXPECT_NEAR(c[row], want, 1e-15) << "row " << row;
      EXPECT_EQ(c_only[row], c[row]) << "row " << row;
      for (int k = 0; k < 12; ++k)
        EXPECT_NEAR(grad[12 * row + k], g[k], 1e-13 * std::max(1.0, std::abs(g[k])))
            << "row " << row << ", coordinate " << k;
    }
  }
}

TEST(Projection, ConvergesFromPerturbedStateWithinFiveIterations) {
  ModelBuilder b;
  b.add_yarn(wavy(30));
  b.add_yarn(wavy(20, 1.0).colwise() + Eigen::Vector3d(0, 2, 0));
  b.add_pin({{0, 0.0}, Eigen::Vector3d::Zero()});
  Model m = b.build(Params{});
  m.pins[0].origin = point_position(m, b.positions(), m.pins[0].at);
  build_constraint_groups(m);  // the groups hold copies of the pins
  FastProjection proj(m);
  Eigen::VectorXd q = test::jitter(b.positions(), 0.03, 17);
  ASSERT_GT(proj.max_violation(m, q, 0.0), 1e-2);
  const ProjectionResult r = proj.project(m, q, 0.0);
  EXPECT_TRUE(r.converged);
  EXPECT_LE(r.iterations, 5);
  EXPECT_LT(proj.max_violation(m, q, 0.0), m.params.solver.constraint_tolerance);
}

// Inextensibility constraints are internal: their gradients sum to zero over a yarn's
// coordinates per axis (translation invariance), so with lumped mass the projection
// Δq = −M⁻¹Gᵀδλ leaves Σ m_k Δq_k = 0: the centre of mass (hence momentum) is unchanged.
TEST(Projection, PreservesCentreOfMassWithoutPins) {
  ModelBuilder b;
  b.add_yarn(wavy(25));
  const Model m = with_constraint_groups(b.build(Params{}));
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
  build_constraint_groups(m);  // the groups hold copies of the pins
  FastProjection proj(m);
  Eigen::VectorXd q = b.positions();
  const ProjectionResult r = proj.project(m, q, 0.05);  // pin target moved 0.05 cm
  ASSERT_TRUE(r.converged) << r.max_violation;
  EXPECT_LT((point_position(m, q, {0, 0.0}) - m.pins[0].target(0.05)).norm(), 1e-6);
  EXPECT_LT((point_position(m, q, {27, 0.5}) - point_position(m, q, {10, 0.5})).norm(), 1e-6);
}

// largest |entry| (a plain loop: GCC 12 warns falsely inside Eigen's AVX-512 max reduction)
double max_abs_of(const Eigen::VectorXd& v) {
  double m = 0;
  for (Eigen::Index k = 0; k < v.size(); ++k) m = std::max(m, std::abs(v[k]));
  return m;
}

// The slow oracle of FastProjection: Goldenthal's iteration written densely — G from the
// constraint kernels and the basis, A = G M⁻¹ Gᵀ as a dense product (with the same relative
// ridge), dense LDLᵀ. Returns the iterations taken.
int dense_projection(const Model& m, Eigen::VectorXd& q, double time) {
  const int len_rows = m.params.solver.length_constraints ? m.num_seg() : 0;
  const int rows = len_rows + 3 * static_cast<int>(m.pins.size() + m.glues.size());
  auto constraints = [&](const Eigen::VectorXd& x, Eigen::MatrixXd& g) {
    Eigen::VectorXd c(rows);
    g.setZero(rows, x.size());
    for (int i = 0; i < len_rows; ++i) {
      Vector12d gi;
      c[i] = length_constraint(gather_segment(x, m.seg_cp[i]), m.rest_length[i], m.quad, &gi);
      g.block<1, 12>(i, 3 * m.seg_cp[i]) = gi.transpose();
    }
    int r = len_rows;
    auto add_point = [&](const YarnPoint& p, double sign) {
      const Eigen::Vector4d b = bspline_basis(p.t);
      for (int a = 0; a < 4; ++a)
        g.block<3, 3>(r, 3 * (m.seg_cp[p.segment] + a)) +=
            sign * b[a] * Eigen::Matrix3d::Identity();
    };
    for (const Pin& pin : m.pins) {
      c.segment<3>(r) = point_position(m, x, pin.at) - pin.target(time);
      add_point(pin.at, 1.0);
      r += 3;
    }
    for (const Glue& glue : m.glues) {
      c.segment<3>(r) = point_position(m, x, glue.a) - point_position(m, x, glue.b);
      add_point(glue.a, 1.0);
      add_point(glue.b, -1.0);
      r += 3;
    }
    return c;
  };
  Eigen::MatrixXd g;
  Eigen::VectorXd c = constraints(q, g);
  int iterations = 0;
  while (max_abs_of(c) > m.params.solver.constraint_tolerance && iterations < 20) {
    Eigen::MatrixXd a = g * m.inv_mass3.asDiagonal() * g.transpose();
    a.diagonal().array() += 1e-12 * max_abs_of(a.diagonal());
    const Eigen::VectorXd dlambda = a.ldlt().solve(c);
    q -= m.inv_mass3.cwiseProduct(g.transpose() * dlambda);
    ++iterations;
    c = constraints(q, g);
  }
  return iterations;
}

// FastProjection (A assembled into a fixed pattern, sparse LDLᵀ) against the dense oracle,
// with length rows, a moving pin and a glue whose two points share control points with
// each other and with the length rows
TEST(Projection, MatchesDenseOracle) {
  for (unsigned seed : {31u, 32u, 33u}) {
    ModelBuilder b;
    b.add_yarn(wavy(18));
    b.add_yarn(wavy(14, 0.5).colwise() + Eigen::Vector3d(0, 0, 0.2));
    Pin pin;
    pin.at = {3, 0.25};
    pin.velocity = Eigen::Vector3d(0.5, 0, 0);
    b.add_pin(pin);
    b.add_glue({{15 + 4, 0.5}, {6, 0.5}});
    b.add_glue({{2, 0.9}, {3, 0.1}});  // two points of neighbouring segments of one yarn
    Model m = b.build(Params{});
    m.pins[0].origin = point_position(m, b.positions(), m.pins[0].at);
    build_constraint_groups(m);  // the groups hold copies of the pins
    const Eigen::VectorXd q0 = test::jitter(b.positions(), 0.02, seed);
    Eigen::VectorXd q_fast = q0, q_dense = q0;
    FastProjection proj(m);
    const ProjectionResult r = proj.project(m, q_fast, 0.02);
    const int dense_iterations = dense_projection(m, q_dense, 0.02);
    ASSERT_TRUE(r.converged) << "seed " << seed;
    ASSERT_GE(r.iterations, 2) << "seed " << seed << ": too easy to compare iterations";
    EXPECT_EQ(r.iterations, dense_iterations) << "seed " << seed;
    const double scale = max_abs_of(q0 - q_dense);
    ASSERT_GT(scale, 1e-4);
    for (Eigen::Index k = 0; k < q0.size(); ++k)
      EXPECT_NEAR(q_fast[k], q_dense[k], 1e-9 * scale) << "seed " << seed << ", coordinate " << k;
  }
}

// the parallel assembly (per entry, fixed term order) makes the projection bitwise
// independent of the thread count
TEST(Projection, DoesNotDependOnThreadCount) {
  ModelBuilder b;
  for (int y = 0; y < 6; ++y)
    b.add_yarn(wavy(300, 0.3 * y).colwise() + Eigen::Vector3d(0, 2.0 * y, 0));
  b.add_glue({{10, 0.5}, {300 + 10, 0.5}});
  const Model m = with_constraint_groups(b.build(Params{}));
  const Eigen::VectorXd q0 = test::jitter(b.positions(), 0.02, 40);
  // an explicit arena: a global_control alone does not raise the concurrency of the
  // thread's implicit arena after its first use
  auto project = [&](int threads) {
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);
    FastProjection proj(m);
    Eigen::VectorXd q = q0;
    tbb::task_arena(threads).execute([&] { EXPECT_TRUE(proj.project(m, q, 0.0).converged); });
    return q;
  };
  const Eigen::VectorXd q1 = project(1), q2 = project(2);
  ASSERT_GT(max_abs_of(q1 - q0), 1e-4);
  for (Eigen::Index k = 0; k < q0.size(); ++k) ASSERT_EQ(q1[k], q2[k]) << "coordinate " << k;
}

}  // namespace
}  // namespace knit
