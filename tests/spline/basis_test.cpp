#include "knit/spline/basis.hpp"

#include <gtest/gtest.h>

#include "knit/model/model.hpp"

namespace knit {
namespace {

TEST(Basis, PartitionOfUnity) {
  for (double t = 0; t <= 1.0; t += 0.05) {
    EXPECT_NEAR(bspline_basis(t).sum(), 1.0, 1e-14) << "t=" << t;
    EXPECT_NEAR(bspline_basis_d1(t).sum(), 0.0, 1e-14) << "t=" << t;
    EXPECT_NEAR(bspline_basis_d2(t).sum(), 0.0, 1e-14) << "t=" << t;
    EXPECT_GE(bspline_basis(t).minCoeff(), 0.0) << "t=" << t;
  }
}

TEST(Basis, DerivativesMatchFiniteDifferences) {
  const double h = 1e-6;
  for (double t = 0.05; t < 1.0; t += 0.1) {
    const Eigen::Vector4d d1 = (bspline_basis(t + h) - bspline_basis(t - h)) / (2 * h);
    const Eigen::Vector4d d2 = (bspline_basis_d1(t + h) - bspline_basis_d1(t - h)) / (2 * h);
    EXPECT_LT((d1 - bspline_basis_d1(t)).norm(), 1e-8) << "t=" << t;
    EXPECT_LT((d2 - bspline_basis_d2(t)).norm(), 1e-8) << "t=" << t;
  }
}

// The end of segment i and the start of segment i+1 share position, tangent and
// curvature: B_{a+1}(0) = B_a(1) for the value and both derivatives.
TEST(Basis, C2ContinuityAcrossSegments) {
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(bspline_basis(1.0)[a + 1], bspline_basis(0.0)[a], 1e-15) << "a=" << a;
    EXPECT_NEAR(bspline_basis_d1(1.0)[a + 1], bspline_basis_d1(0.0)[a], 1e-15) << "a=" << a;
    EXPECT_NEAR(bspline_basis_d2(1.0)[a + 1], bspline_basis_d2(0.0)[a], 1e-15) << "a=" << a;
  }
  EXPECT_NEAR(bspline_basis(1.0)[0], 0.0, 1e-15);
  EXPECT_NEAR(bspline_basis(0.0)[3], 0.0, 1e-15);
  // and on a random curve
  Eigen::Matrix<double, 3, 5> cp;
  cp.setRandom();
  const Eigen::Vector3d end0 = cp.leftCols<4>() * bspline_basis(1.0);
  const Eigen::Vector3d start1 = cp.rightCols<4>() * bspline_basis(0.0);
  const Eigen::Vector3d t0 = cp.leftCols<4>() * bspline_basis_d1(1.0);
  const Eigen::Vector3d t1 = cp.rightCols<4>() * bspline_basis_d1(0.0);
  const Eigen::Vector3d k0 = cp.leftCols<4>() * bspline_basis_d2(1.0);
  const Eigen::Vector3d k1 = cp.rightCols<4>() * bspline_basis_d2(0.0);
  EXPECT_LT((end0 - start1).norm(), 1e-14);
  EXPECT_LT((t0 - t1).norm(), 1e-14);
  EXPECT_LT((k0 - k1).norm(), 1e-14);
}

TEST(Basis, SimpsonIsExactForCubicsAndIntegratesBasis) {
  const QuadratureTable q = simpson_table(11);
  double sum_w = 0, cubic = 0;
  Eigen::Vector4d ib = Eigen::Vector4d::Zero();
  for (int k = 0; k < q.size(); ++k) {
    sum_w += q.w[k];
    cubic += q.w[k] * q.t[k] * q.t[k] * q.t[k];
    ib += q.w[k] * q.b[k];
  }
  EXPECT_NEAR(sum_w, 1.0, 1e-14);
  EXPECT_NEAR(cubic, 0.25, 1e-14);
  // each B_a is a cubic polynomial on [0,1], so Simpson integrates it exactly
  EXPECT_NEAR(ib[0], 1.0 / 24, 1e-14);
  EXPECT_NEAR(ib[1], 11.0 / 24, 1e-14);
  EXPECT_NEAR(ib[2], 11.0 / 24, 1e-14);
  EXPECT_NEAR(ib[3], 1.0 / 24, 1e-14);
  EXPECT_THROW(simpson_table(10), std::invalid_argument);
  EXPECT_THROW(midpoint_table(0), std::invalid_argument);
}

// The exact banded mass matrix M_kl = μ Σ_i ℓ_i ∫ B_{k−i} B_{l−i} has row sums equal to the
// lumped diagonal M_k = μ Σ_i ℓ_i ∫ B_{k−i} (partition of unity), which the model uses.
TEST(Basis, LumpedMassEqualsExactMassRowSums) {
  Eigen::Matrix3Xd cp(3, 9);
  for (int k = 0; k < 9; ++k) cp.col(k) = Eigen::Vector3d(k * 0.4, 0.3 * std::sin(k), 0.1 * k * k);
  ModelBuilder b;
  b.add_yarn(cp);
  const Model m = b.build(Params{});
  const int n = m.num_cp();
  // exact mass with a high-order quadrature of B_a B_b
  const QuadratureTable q = simpson_table(201);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < m.num_seg(); ++i)
    for (int k = 0; k < q.size(); ++k)
      for (int a = 0; a < 4; ++a)
        for (int c = 0; c < 4; ++c)
          M(i + a, i + c) +=
              m.params.material.density * m.rest_length[i] * q.w[k] * q.b[k][a] * q.b[k][c];
  for (int k = 0; k < n; ++k) EXPECT_NEAR(M.row(k).sum(), m.mass[k], 1e-9) << "control point " << k;
  // total mass is μ × total length
  EXPECT_NEAR(m.mass.sum(), m.params.material.density * m.total_length(), 1e-12);
}

// Discretisation::end_mass_floor raises the two control points at each end of a yarn to
// that fraction of the yarn's mean interior control point, and leaves every other one
// (and every other yarn's short ends) as the row sums make them.
TEST(Basis, EndMassFloorRaisesOnlyTheYarnEnds) {
  Eigen::Matrix3Xd cp(3, 20);
  for (int k = 0; k < 20; ++k)
    cp.col(k) = Eigen::Vector3d(k * 0.4, 0.3 * std::sin(k), 0.01 * k * k);
  ModelBuilder b;
  b.add_yarn(cp);
  b.add_yarn(cp.leftCols(6).colwise() + Eigen::Vector3d(0, 5, 0));  // too short for a floor
  const Model plain = b.build(Params{});
  Params p;
  p.discretisation.end_mass_floor = 0.5;
  const Model floored = b.build(p);
  double interior = 0;
  for (int k = 3; k < 17; ++k) interior += plain.mass[k];
  interior /= 14;
  EXPECT_NEAR(plain.mass[0], interior / 24, 0.05 * interior);  // the row sums' 1/24
  for (int k = 0; k < plain.num_cp(); ++k) {
    const bool end = k < 2 || (k >= 18 && k < 20);
    const double expected = end ? std::max(plain.mass[k], 0.5 * interior) : plain.mass[k];
    EXPECT_DOUBLE_EQ(floored.mass[k], expected) << "control point " << k;
    EXPECT_DOUBLE_EQ(floored.inv_mass3[3 * k], 1 / expected) << "control point " << k;
  }
  EXPECT_GT(floored.mass[0], 10 * plain.mass[0]);
  p.discretisation.end_mass_floor = 1.5;
  EXPECT_THROW(validate_params(p), std::invalid_argument);
}

}  // namespace
}  // namespace knit
