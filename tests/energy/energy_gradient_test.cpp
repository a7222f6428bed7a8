// Finite-difference checks of every energy and damping gradient, per segment kernel and
// assembled over a yarn, including a straight yarn, a tight bend and coincident points.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "fd_check.hpp"
#include "knit/energy/bending.hpp"
#include "knit/energy/global_damping.hpp"
#include "knit/energy/gravity.hpp"
#include "knit/energy/length.hpp"

namespace knit {
namespace {

using test::expect_gradient_matches;

Vector12d straight_segment() {
  Vector12d x;
  for (int a = 0; a < 4; ++a) x.segment<3>(3 * a) = Eigen::Vector3d(0.3 * a, 0.1 * a, 0);
  return x;
}

Vector12d bent_segment() {  // a tight bend: control points on a small circle
  Vector12d x;
  for (int a = 0; a < 4; ++a)
    x.segment<3>(3 * a) = 0.2 * Eigen::Vector3d(std::cos(1.2 * a), std::sin(1.2 * a), 0.1 * a);
  return x;
}

Vector12d coincident_segment() {  // control points 1 and 2 coincide
  Vector12d x = bent_segment();
  x.segment<3>(6) = x.segment<3>(3);
  return x;
}

struct Case {
  const char* name;
  Vector12d x;
};

std::vector<Case> cases() {
  return {{"straight", straight_segment()},
          {"bent", bent_segment()},
          {"coincident", coincident_segment()},
          {"random", test::jitter(bent_segment(), 0.05, 7)}};
}

TEST(EnergyKernels, BendingGradientMatchesFiniteDifferences) {
  const QuadratureTable q = simpson_table(11);
  for (const Case& c : cases()) {
    // a straight yarn has zero bending gradient; perturb it off the line to test the kernel
    const Vector12d x =
        std::string(c.name) == "straight" ? Vector12d(test::jitter(c.x, 0.02, 3)) : c.x;
    Vector12d g = Vector12d::Zero();
    bending_kernel(x, 0.5, 5.0, q, &g);
    auto f = [&](const Eigen::VectorXd& y) {
      return bending_kernel(Vector12d(y), 0.5, 5.0, q, nullptr);
    };
    expect_gradient_matches(f, x, g, 1e-7, 1e-5, std::string("bending/") + c.name);
  }
}

// The length energy's Hessian (the implicit integrator's stiffness): column k of the exact
// Hessian is the central difference of the analytic gradient along coordinate k; the
// projected one is symmetric positive semidefinite, and equals the exact one where no
// quadrature point is compressed.
TEST(EnergyKernels, LengthHessianMatchesFiniteDifferencesOfTheGradient) {
  const QuadratureTable q = simpson_table(11);
  for (const Case& c : cases()) {
    for (double stretch : {0.9, 1.1}) {  // rest length below / above the arc length
      const double rest = stretch * segment_arclength(c.x, q);
      const Matrix12d hess = length_hessian(c.x, rest, 2000.0, q, LengthHessian::EXACT);
      const double eps = 1e-6;
      Matrix12d fd;
      for (int k = 0; k < 12; ++k) {
        Vector12d xp = c.x, xm = c.x, gp = Vector12d::Zero(), gm = Vector12d::Zero();
        xp[k] += eps;
        xm[k] -= eps;
        length_kernel(xp, rest, 2000.0, q, &gp);
        length_kernel(xm, rest, 2000.0, q, &gm);
        fd.col(k) = (gp - gm) / (2 * eps);
      }
      const std::string what =
          std::string("length Hessian/") + c.name + (stretch < 1 ? "/stretched" : "/compressed");
      const double scale = fd.cwiseAbs().maxCoeff();
      ASSERT_GT(scale, 0.0) << what;
      EXPECT_LT((hess - fd).cwiseAbs().maxCoeff(), 1e-5 * scale) << what;
      const Matrix12d proj = length_hessian(c.x, rest, 2000.0, q, LengthHessian::PROJECTED);
      EXPECT_LT((proj - proj.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale) << what;
      const Eigen::SelfAdjointEigenSolver<Matrix12d> eig(proj);
      EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-10 * scale) << what;
      // evenly spaced control points on a line: uniform speed, stretched everywhere
      if (stretch < 1 && std::string(c.name) == "straight")
        EXPECT_LT((proj - hess).cwiseAbs().maxCoeff(), 1e-12 * scale) << what;
    }
  }
}

// The bending energy's Hessian (the stiffness of implicit bending): column k of the exact
// Hessian is the central difference of the analytic gradient along coordinate k (straight
// off the line, tight bend, coincident control points, random); the projected one is
// symmetric positive semidefinite and equals the exact one where that is semidefinite.
TEST(EnergyKernels, BendingHessianMatchesFiniteDifferencesOfTheGradient) {
  const QuadratureTable q = simpson_table(11);
  for (const Case& c : cases()) {
    const Vector12d x =
        std::string(c.name) == "straight" ? Vector12d(test::jitter(c.x, 0.02, 3)) : c.x;
    const Matrix12d hess = bending_hessian(x, 0.5, 5.0, q, BendingHessian::EXACT);
    const double eps = 1e-6;
    Matrix12d fd;
    for (int k = 0; k < 12; ++k) {
      Vector12d xp = x, xm = x, gp = Vector12d::Zero(), gm = Vector12d::Zero();
      xp[k] += eps;
      xm[k] -= eps;
      bending_kernel(xp, 0.5, 5.0, q, &gp);
      bending_kernel(xm, 0.5, 5.0, q, &gm);
      fd.col(k) = (gp - gm) / (2 * eps);
    }
    const std::string what = std::string("bending Hessian/") + c.name;
    const double scale = fd.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0) << what;
    EXPECT_LT((hess - fd).cwiseAbs().maxCoeff(), 1e-5 * scale) << what;
    // moving the segment as a whole changes nothing: H annihilates the translations (the
    // projection works across them)
    for (int axis = 0; axis < 3; ++axis) {
      Vector12d t = Vector12d::Zero();
      for (int a = 0; a < 4; ++a) t[3 * a + axis] = 1;
      EXPECT_LT((hess * t).cwiseAbs().maxCoeff(), 1e-9 * scale) << what << " axis " << axis;
    }
    const Matrix12d proj = bending_hessian(x, 0.5, 5.0, q, BendingHessian::PROJECTED);
    ASSERT_TRUE(proj.allFinite()) << what;
    EXPECT_LT((proj - proj.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale) << what;
    const Eigen::SelfAdjointEigenSolver<Matrix12d> ep(proj), ee(hess);
    EXPECT_GT(ep.eigenvalues().minCoeff(), -1e-10 * scale) << what;
    if (ee.eigenvalues().minCoeff() >= 0)
      EXPECT_LT((proj - hess).cwiseAbs().maxCoeff(), 1e-9 * scale) << what;
    else  // what the projection removed is the negative part only
      EXPECT_GT((proj - hess).cwiseAbs().maxCoeff(), 0.0) << what;
  }
  // a straight yarn: every bending mode is stiff or free, none negative
  const Matrix12d straight =
      bending_hessian(straight_segment(), 0.5, 5.0, q, BendingHessian::EXACT);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix12d>(straight).eigenvalues().minCoeff(),
            -1e-9 * straight.cwiseAbs().maxCoeff());
}

TEST(EnergyKernels, StraightYarnHasZeroBendingEnergyAndForce) {
  const QuadratureTable q = simpson_table(11);
  Vector12d g = Vector12d::Zero();
  EXPECT_NEAR(bending_kernel(straight_segment(), 0.5, 5.0, q, &g), 0.0, 1e-20);
  EXPECT_LT(g.norm(), 1e-12);
}

TEST(EnergyKernels, LengthGradientMatchesFiniteDifferences) {
  const QuadratureTable q = simpson_table(11);
  for (const Case& c : cases()) {
    Vector12d g = Vector12d::Zero();
    length_kernel(c.x, 0.9 * segment_arclength(c.x, q), 2000.0, q, &g);
    auto f = [&](const Eigen::VectorXd& y) {
      return length_kernel(Vector12d(y), 0.9 * segment_arclength(c.x, q), 2000.0, q, nullptr);
    };
    expect_gradient_matches(f, c.x, g, 1e-7, 1e-6, std::string("length/") + c.name);
  }
}

TEST(EnergyKernels, GlobalDampingGradientMatchesFiniteDifferences) {
  const Vector12d u = test::jitter(Vector12d::Zero(), 3.0, 11);
  Vector12d g = Vector12d::Zero();
  global_damping_kernel(u, 1.5, &g);
  auto f = [&](const Eigen::VectorXd& y) {
    return global_damping_kernel(Vector12d(y), 1.5, nullptr);
  };
  expect_gradient_matches(f, u, g, 1e-6, 1e-8, "global_damping");
}

// assembled terms over a small yarn: force = −∇E
Model wavy_yarn(Eigen::VectorXd& q) {
  Eigen::Matrix3Xd cp(3, 12);
  for (int k = 0; k < 12; ++k)
    cp.col(k) = Eigen::Vector3d(0.3 * k, 0.2 * std::sin(0.9 * k), 0.1 * std::cos(1.3 * k));
  ModelBuilder b;
  b.add_yarn(cp);
  b.add_yarn(cp.colwise() + Eigen::Vector3d(0, 1, 0));
  q = b.positions();
  return b.build(Params{}, 0.95);
}

template <class T>
void check_assembled(const char* name) {
  Eigen::VectorXd q;
  const Model m = wavy_yarn(q);
  q = test::jitter(q, 0.02, 5);
  T term;
  Eigen::VectorXd f = Eigen::VectorXd::Zero(q.size());
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(q.size());
  term.add_force(m, q, v, 0.0, f);
  auto e = [&](const Eigen::VectorXd& y) {
    Eigen::VectorXd tmp = Eigen::VectorXd::Zero(y.size());
    return term.add_force(m, y, v, 0.0, tmp);
  };
  expect_gradient_matches(e, q, -f, 1e-7, 1e-5, name);
  // energy() agrees with add_force's return value
  Eigen::VectorXd tmp = Eigen::VectorXd::Zero(q.size());
  EXPECT_NEAR(term.energy(m, q, 0.0), term.add_force(m, q, v, 0.0, tmp),
              1e-9 * (1 + std::abs(e(q))));
}

TEST(AssembledEnergies, BendingForceIsMinusGradient) {
  check_assembled<BendingEnergy>("bending");
}
TEST(AssembledEnergies, LengthForceIsMinusGradient) {
  check_assembled<LengthEnergy>("length");
}
TEST(AssembledEnergies, GravityForceIsMinusGradient) {
  check_assembled<Gravity>("gravity");
}

TEST(AssembledEnergies, GlobalDampingForceIsMinusVelocityGradientAndDissipates) {
  Eigen::VectorXd q;
  Model m = wavy_yarn(q);
  m.params.material.k_global = 1.5;
  const Eigen::VectorXd v = test::jitter(Eigen::VectorXd::Zero(q.size()), 4.0, 9);
  GlobalDamping term;
  Eigen::VectorXd f = Eigen::VectorXd::Zero(q.size());
  term.add_force(m, q, v, 0.0, f);
  auto d = [&](const Eigen::VectorXd& u) {
    double sum = 0;
    for (int i = 0; i < m.num_seg(); ++i)
      sum += global_damping_kernel(gather_segment(u, m.seg_cp[i]), 1.5, nullptr);
    return sum;
  };
  expect_gradient_matches(d, v, -f, 1e-6, 1e-7, "global_damping assembled");
  EXPECT_LT(f.dot(v), 0.0) << "damping must remove energy";
}

// Mass-proportional (MODEL.md §4, lumped like the mass): on a yarn whose segments all have
// rest length ℓ, the damping force on control point k is exactly −λ m_k v_k with
// λ = 2 k_global / (μ ℓ): D's weight on q̇_k is k_global Σ_i ∫B_{k−i}, the mass
// m_k = μ ℓ Σ_i ∫B_{k−i}. (Its effect on the motion:
// Dynamics.GlobalDampingDecaysATranslatingYarnExponentially.)
TEST(AssembledEnergies, GlobalDampingIsMassProportional) {
  Eigen::Matrix3Xd cp(3, 14);
  const double ell = 0.4;
  for (int k = 0; k < 14; ++k) cp.col(k) = Eigen::Vector3d((k - 1) * ell, 0.5, -1);
  ModelBuilder b;
  b.add_yarn(cp);
  Params p;
  p.material.k_global = 1.5;
  const Model m = b.build(p, 0.935);  // shrunk rest lengths leave mass and damping alone
  const Eigen::VectorXd v = test::jitter(Eigen::VectorXd::Zero(m.num_dof()), 4.0, 13);
  GlobalDamping term;
  Eigen::VectorXd f = Eigen::VectorXd::Zero(v.size());
  term.add_force(m, b.positions(), v, 0.0, f);
  const double lambda = 2 * 1.5 / (p.material.density * ell);  // 1250 /s
  for (int k = 0; k < m.num_cp(); ++k)
    EXPECT_LT((f.segment<3>(3 * k) + lambda * m.mass[k] * v.segment<3>(3 * k)).norm(),
              1e-12 * lambda * m.mass[k] * v.segment<3>(3 * k).norm())
        << "control point " << k;
}

}  // namespace
}  // namespace knit
