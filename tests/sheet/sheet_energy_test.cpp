// Finite-difference checks of the Baraff–Witkin sheet conditions (src/knit/sheet/
// bw_energy.hpp): gradients and exact Hessians per kernel on random triangles and hinges,
// the assembled forces and Jacobians on a small mesh, the damping Jacobian, and the rest
// mesh's zero energy and force.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include "fd_check.hpp"
#include "knit/sheet/bw_energy.hpp"
#include "knit/sheet/sheet.hpp"

namespace knit::sheet {
namespace {

using test::expect_gradient_matches;
using test::jitter;

// central-difference Jacobian of g at x, compared entry by entry with `analytic` within
// rel · max|J|; the Jacobian must be non-zero
void expect_jacobian_matches(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& g,
                             const Eigen::VectorXd& x, const Eigen::MatrixXd& analytic, double h,
                             double rel, const std::string& what) {
  Eigen::MatrixXd fd(analytic.rows(), x.size());
  Eigen::VectorXd y = x;
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    y[k] = x[k] + h;
    const Eigen::VectorXd gp = g(y);
    y[k] = x[k] - h;
    const Eigen::VectorXd gm = g(y);
    y[k] = x[k];
    fd.col(k) = (gp - gm) / (2 * h);
  }
  const double scale = std::max(fd.cwiseAbs().maxCoeff(), analytic.cwiseAbs().maxCoeff());
  ASSERT_GT(scale, 0.0) << what << ": Jacobian is zero; the check would be vacuous";
  int failures = 0;
  for (Eigen::Index r = 0; r < fd.rows() && failures < 10; ++r)
    for (Eigen::Index c = 0; c < fd.cols() && failures < 10; ++c)
      if (std::abs(analytic(r, c) - fd(r, c)) > rel * scale) {
        ++failures;
        ADD_FAILURE() << what << ": entry (" << r << ", " << c << ") analytic " << analytic(r, c)
                      << " vs finite difference " << fd(r, c) << " (scale " << scale << ")";
      }
}

struct RestTriangle {
  Eigen::Matrix2d dinv;
  double area;
  Vector9d x;  // a deformed configuration
};

// a random material triangle, embedded in 3-D by a random rotation, then deformed
RestTriangle random_triangle(unsigned seed, double deformation) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Matrix<double, 2, 3> uv;
  uv << 0, 0.8 + 0.2 * u(rng), 0.2 * u(rng), 0, 0.2 * u(rng), 0.7 + 0.2 * u(rng);
  Eigen::Matrix2d d;
  d.col(0) = uv.col(1) - uv.col(0);
  d.col(1) = uv.col(2) - uv.col(0);
  RestTriangle t;
  t.dinv = d.inverse();
  t.area = 0.5 * std::abs(d.determinant());
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(3 * u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized())
          .toRotationMatrix();
  for (int k = 0; k < 3; ++k) t.x.segment<3>(3 * k) = rot * Eigen::Vector3d(uv(0, k), uv(1, k), 0);
  t.x = jitter(t.x, deformation, seed + 100);
  return t;
}

// a hinge folded by `fold` radians, jittered
Vector12d random_hinge(double fold, unsigned seed) {
  Vector12d x;
  x.segment<3>(0) = Eigen::Vector3d(0.4, 1.0, 0);                                 // x1
  x.segment<3>(3) = Eigen::Vector3d(0.6, -std::cos(fold), std::sin(fold)) * 1.1;  // x2
  x.segment<3>(6) = Eigen::Vector3d(0, 0, 0);                                     // x3
  x.segment<3>(9) = Eigen::Vector3d(1.2, 0, 0);                                   // x4
  return jitter(x, 0.05, seed);
}

constexpr double K = 3.0;  // any stiffness: the checks are relative

TEST(SheetKernels, StretchGradientAndHessianMatchFiniteDifferences) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const RestTriangle t = random_triangle(seed, 0.2);
    const std::string what = "stretch/seed " + std::to_string(seed);
    Vector9d g = Vector9d::Zero();
    Matrix9d h = Matrix9d::Zero();
    stretch_energy(t.x, t.dinv, t.area, K, 1.7 * K, &g, &h, HessianKind::EXACT);
    auto e = [&](const Eigen::VectorXd& y) {
      return stretch_energy(Vector9d(y), t.dinv, t.area, K, 1.7 * K, nullptr, nullptr);
    };
    expect_gradient_matches(e, t.x, g, 1e-6, 1e-6, what);
    auto grad = [&](const Eigen::VectorXd& y) {
      Vector9d gy = Vector9d::Zero();
      stretch_energy(Vector9d(y), t.dinv, t.area, K, 1.7 * K, &gy, nullptr);
      return Eigen::VectorXd(gy);
    };
    expect_jacobian_matches(grad, t.x, h, 1e-6, 1e-5, what);
  }
}

TEST(SheetKernels, ShearGradientAndHessianMatchFiniteDifferences) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const RestTriangle t = random_triangle(seed, 0.2);
    const std::string what = "shear/seed " + std::to_string(seed);
    Vector9d g = Vector9d::Zero();
    Matrix9d h = Matrix9d::Zero();
    shear_energy(t.x, t.dinv, t.area, K, &g, &h, HessianKind::EXACT);
    auto e = [&](const Eigen::VectorXd& y) {
      return shear_energy(Vector9d(y), t.dinv, t.area, K, nullptr, nullptr);
    };
    expect_gradient_matches(e, t.x, g, 1e-6, 1e-6, what);
    auto grad = [&](const Eigen::VectorXd& y) {
      Vector9d gy = Vector9d::Zero();
      shear_energy(Vector9d(y), t.dinv, t.area, K, &gy, nullptr);
      return Eigen::VectorXd(gy);
    };
    expect_jacobian_matches(grad, t.x, h, 1e-6, 1e-5, what);
  }
}

TEST(SheetKernels, BendAngleIsTheSignedDihedralAngle) {
  for (double fold : {0.0, 0.3, 1.0, 2.0, 2.8}) {
    Vector12d x;
    x << 0.4, 1, 0, 0.6 * 1.1, -std::cos(fold) * 1.1, std::sin(fold) * 1.1, 0, 0, 0, 1.2, 0, 0;
    EXPECT_NEAR(bend_angle(x), -fold, 1e-12) << "fold " << fold;  // both wings up: θ < 0
    x(5) = -x(5);
    EXPECT_NEAR(bend_angle(x), fold, 1e-12) << "fold " << fold;
  }
}

TEST(SheetKernels, BendGradientAndHessianMatchFiniteDifferences) {
  const double folds[] = {0.0, 0.4, -1.2, 2.5};
  unsigned seed = 1;
  for (double fold : folds)
    for (double rest : {0.0, 0.3}) {
      const Vector12d x = random_hinge(fold, ++seed);
      // the triangles' areas 1.25× their rest areas in product: the weight is not 1
      const double rp = 0.8 * bend_area_product(x);
      const std::string what =
          "bend/fold " + std::to_string(fold) + " rest " + std::to_string(rest);
      Vector12d g = Vector12d::Zero();
      Matrix12d h = Matrix12d::Zero();
      bend_energy(x, rest, rp, K, &g, &h, HessianKind::EXACT);
      auto e = [&](const Eigen::VectorXd& y) {
        return bend_energy(Vector12d(y), rest, rp, K, nullptr, nullptr);
      };
      expect_gradient_matches(e, x, g, 1e-6, 1e-6, what);
      auto grad = [&](const Eigen::VectorXd& y) {
        Vector12d gy = Vector12d::Zero();
        bend_energy(Vector12d(y), rest, rp, K, &gy, nullptr);
        return Eigen::VectorXd(gy);
      };
      expect_jacobian_matches(grad, x, h, 1e-6, 1e-5, what);
      // the condition's own gradient, too (flat hinges have C = 0 and a zero energy gradient)
      const Condition<12> c = bend_condition(x, rest, rp, false);
      EXPECT_NEAR(c.c, 1.25 * (bend_angle(x) - rest), 1e-12) << what;
      auto cond = [&](const Eigen::VectorXd& y) {
        return bend_condition(Vector12d(y), rest, rp, false).c;
      };
      expect_gradient_matches(cond, x, c.grad, 1e-6, 1e-6, what + " ∂C/∂x");
    }
}

// BW's bend condition θ − θ₀ has a force ∝ 1/‖n‖ as a triangle of the hinge collapses (its
// normal, and θ, lose their meaning); weighted by the triangles' areas, C_b's energy gradient
// and Hessian stay bounded and go to zero with the area.
TEST(SheetKernels, BendForceStaysBoundedAsATriangleCollapses) {
  const Vector12d x0 = random_hinge(0.8, 7);
  const double rp = bend_area_product(x0), rest = 0.1;
  const Eigen::Vector3d x3 = x0.segment<3>(6), x4 = x0.segment<3>(9);
  const Eigen::Vector3d e = (x4 - x3).normalized();
  // x1's distance from the edge's line, and its foot on it
  const Eigen::Vector3d foot = x3 + (x0.segment<3>(0) - x3).dot(e) * e;
  const double d0 = (x0.segment<3>(0) - foot).norm();
  double previous_theta_gradient = 0, g1 = 0, h1 = 0;
  for (double scale : {1.0, 1e-2, 1e-4, 1e-6}) {
    Vector12d x = x0;  // x1 moved toward the edge: triangle (x1, x3, x4) collapses
    x.segment<3>(0) = foot + scale * (x0.segment<3>(0) - foot);
    const std::string what = "x1 at " + std::to_string(scale * d0) + " cm from the edge";
    Vector12d g = Vector12d::Zero();
    Matrix12d h = Matrix12d::Zero();
    const double energy = bend_energy(x, rest, rp, K, &g, &h, HessianKind::EXACT);
    ASSERT_TRUE(g.allFinite() && h.allFinite()) << what;
    if (scale == 1) {
      g1 = g.norm();
      h1 = h.norm();
      ASSERT_GT(g1, 0);
    }
    // w = scale here: the energy ½ k w² (θ − θ₀)² ≤ ½ k π² scale², the gradient O(scale),
    // the Hessian bounded
    EXPECT_LE(energy, 0.5 * K * std::numbers::pi * std::numbers::pi * scale * scale) << what;
    EXPECT_LE(g.norm(), 10 * g1 * scale) << what;
    EXPECT_LE(h.norm(), 10 * h1) << what;
    // while θ's own gradient ‖∂θ/∂x1‖ = ‖e‖/‖n1‖ grows as 1/distance: the weight is what
    // bounds the force
    const Eigen::Vector3d x1 = x.segment<3>(0);
    const double theta_gradient = (x4 - x3).norm() / (x1 - x3).cross(x1 - x4).norm();
    if (scale < 1) EXPECT_GT(theta_gradient, 50 * previous_theta_gradient) << what;
    previous_theta_gradient = theta_gradient;
  }
  // collapsed (to round-off): no bend energy and no force
  Vector12d x = x0;
  x.segment<3>(0) = foot;
  Vector12d g = Vector12d::Zero();
  EXPECT_LE(bend_energy(x, rest, rp, K, &g, nullptr), 1e-24);
  EXPECT_LE(g.norm(), 1e-12);
}

TEST(SheetKernels, BendConditionRejectsAZeroRestArea) {
  const Vector12d x = random_hinge(0.3, 1);
  for (double rp : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN()})
    EXPECT_THROW(bend_condition(x, 0.0, rp, false), std::invalid_argument) << rp;
}

TEST(SheetKernels, PsdHessiansArePositiveSemiDefinite) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    for (double deformation : {0.05, 0.3}) {
      const RestTriangle t = random_triangle(seed, deformation);
      Matrix9d h = Matrix9d::Zero();
      stretch_energy(t.x, t.dinv, t.area, K, 1.7 * K, nullptr, &h, HessianKind::PSD);
      shear_energy(t.x, t.dinv, t.area, K, nullptr, &h, HessianKind::PSD);
      EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix9d>(h).eigenvalues().minCoeff(),
                -1e-12 * h.norm());
    }
    Matrix12d hb = Matrix12d::Zero();
    const Vector12d xb = random_hinge(1.0, seed);
    bend_energy(xb, 0.2, 0.9 * bend_area_product(xb), K, nullptr, &hb, HessianKind::PSD);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix12d>(hb).eigenvalues().minCoeff(),
              -1e-12 * hb.norm());
  }
}

TEST(SheetKernels, DampingForceVelocityJacobianMatchesFiniteDifferences) {
  const RestTriangle t = random_triangle(3, 0.2);
  const Vector9d v = jitter(Vector9d::Zero(), 5.0, 11);
  const auto cs = stretch_conditions(t.x, t.dinv, t.area, false);
  Vector9d f = Vector9d::Zero();
  Matrix9d dfdv = Matrix9d::Zero();
  condition_damping(cs[0], v, 2.0, &f, &dfdv);
  auto force = [&](const Eigen::VectorXd& w) {
    Vector9d fw = Vector9d::Zero();
    condition_damping(cs[0], Vector9d(w), 2.0, &fw, nullptr);
    return Eigen::VectorXd(fw);
  };
  expect_jacobian_matches(force, v, dfdv, 1e-3, 1e-9, "stretch damping");
  // the damping force opposes the condition's rate: f·v = −k_d Ċ² ≤ 0
  EXPECT_LT(f.dot(v), 0.0);
}

SheetMaterial test_material() {
  SheetMaterial m;
  m.k_stretch_u = 50;
  m.k_stretch_v = 70;
  m.k_shear = 20;
  m.k_bend = 3;
  m.d_stretch = 0.5;
  m.d_shear = 0.2;
  m.d_bend = 0.1;
  return m;
}

SheetMesh small_mesh() {
  return make_rectangle(Eigen::Vector3d(0.1, -0.2, 0.3), Eigen::Vector3d(1, 0.2, 0),
                        Eigen::Vector3d(0, 0.3, 1), 2.0, 1.5, 4, 3, 0.05);
}

TEST(SheetAssembly, ForcesAndJacobiansMatchFiniteDifferences) {
  const SheetMesh mesh = small_mesh();
  const SheetMaterial mat = test_material();
  const Eigen::Vector3d gravity(0.5, -1, -9.81);
  const Eigen::VectorXd x = jitter(mesh.rest_positions(), 0.15, 5);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(mesh.num_dofs());
  const Eigen::VectorXd v = jitter(zero, 2.0, 6);

  const SheetForces f = evaluate_forces(mesh, mat, x, zero, gravity, Jacobians::EXACT);
  EXPECT_NEAR(f.energy(), potential_energy(mesh, mat, x, gravity), 1e-12 * std::abs(f.energy()));
  auto energy = [&](const Eigen::VectorXd& y) { return potential_energy(mesh, mat, y, gravity); };
  expect_gradient_matches(energy, x, -f.force, 1e-6, 1e-6, "assembled force");
  auto force_x = [&](const Eigen::VectorXd& y) {
    return evaluate_forces(mesh, mat, y, zero, gravity, Jacobians::NONE).force;
  };
  expect_jacobian_matches(force_x, x, Eigen::MatrixXd(f.dfdx), 1e-6, 1e-5, "assembled ∂f/∂x");

  const SheetForces fv = evaluate_forces(mesh, mat, x, v, gravity, Jacobians::PSD);
  auto force_v = [&](const Eigen::VectorXd& w) {
    return evaluate_forces(mesh, mat, x, w, gravity, Jacobians::NONE).force;
  };
  expect_jacobian_matches(force_v, v, Eigen::MatrixXd(fv.dfdv), 1e-3, 1e-8, "assembled ∂f/∂v");

  // the PSD stiffness is negative semi-definite and, like the exact one, translation
  // invariant (each node row's blocks sum to zero)
  const Eigen::MatrixXd kp(fv.dfdx);
  EXPECT_LT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(kp).eigenvalues().maxCoeff(),
            1e-10 * kp.norm());
  for (const Eigen::MatrixXd& k : {kp, Eigen::MatrixXd(f.dfdx)}) {
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(k.rows(), 3);
    for (int j = 0; j < mesh.num_nodes(); ++j) sum += k.middleCols(3 * j, 3);
    EXPECT_LT(sum.cwiseAbs().maxCoeff(), 1e-10 * k.cwiseAbs().maxCoeff());
  }
}

TEST(SheetAssembly, CachedPatternAssemblyMatchesTriplets) {
  // the fast path (blocks added into the mesh's cached pattern) against the plain one
  const SheetMesh mesh = small_mesh();
  SheetMesh plain = mesh;
  plain.jacobian_pattern = Eigen::SparseMatrix<double>();
  const Eigen::VectorXd x = jitter(mesh.rest_positions(), 0.15, 8);
  const Eigen::VectorXd v = jitter(Eigen::VectorXd::Zero(mesh.num_dofs()), 2.0, 9);
  for (Jacobians kind : {Jacobians::PSD, Jacobians::EXACT, Jacobians::PROJECTED}) {
    const SheetForces a = evaluate_forces(mesh, test_material(), x, v, {0, 0, -9.81}, kind);
    const SheetForces b = evaluate_forces(plain, test_material(), x, v, {0, 0, -9.81}, kind);
    const double scale = Eigen::MatrixXd(b.dfdx).cwiseAbs().maxCoeff();
    EXPECT_LT(Eigen::MatrixXd(a.dfdx - b.dfdx).cwiseAbs().maxCoeff(), 1e-13 * scale);
    EXPECT_LT(Eigen::MatrixXd(a.dfdv - b.dfdv).cwiseAbs().maxCoeff(),
              1e-13 * Eigen::MatrixXd(b.dfdv).cwiseAbs().maxCoeff());
    EXPECT_EQ(a.force, b.force);
    // evaluated into the matrices of an earlier evaluation (another state, or none asked
    // for), which it reuses: the same as a fresh one
    for (Jacobians before : {kind, Jacobians::NONE}) {
      SheetForces reused;
      evaluate_forces(mesh, test_material(), mesh.rest_positions(), 2 * v, {1, 0, 0}, before,
                      reused);
      evaluate_forces(mesh, test_material(), x, v, {0, 0, -9.81}, kind, reused);
      EXPECT_EQ(reused.force, a.force);
      EXPECT_EQ(reused.energy(), a.energy());
      EXPECT_EQ(reused.bend_energy, a.bend_energy);
      EXPECT_EQ(Eigen::MatrixXd(reused.dfdx), Eigen::MatrixXd(a.dfdx));
      EXPECT_EQ(Eigen::MatrixXd(reused.dfdv), Eigen::MatrixXd(a.dfdv));
    }
  }
  SheetForces none;  // and NONE leaves no matrices behind
  evaluate_forces(mesh, test_material(), mesh.rest_positions(), mesh.rest_positions(), {0, 0, 0},
                  Jacobians::PSD, none);
  evaluate_forces(mesh, test_material(), mesh.rest_positions(), mesh.rest_positions(), {0, 0, 0},
                  Jacobians::NONE, none);
  EXPECT_EQ(none.dfdx.nonZeros(), 0);
  EXPECT_EQ(none.dfdv.nonZeros(), 0);
}

// The projected Hessian (each element's exact Hessian with its negative eigenvalues set to
// zero) is the exact one plus each element's negative part: so H_proj is PSD, H_proj − H_exact
// is PSD, both carry the rigid translations in their null space, and where every element's
// exact Hessian is PSD already (uniform tension with no shear or fold) they are equal.
TEST(SheetAssembly, ProjectedHessianIsTheExactOneMadePositive) {
  const SheetMesh mesh = small_mesh();
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(mesh.num_dofs());
  const Eigen::Vector3d g(0, 0, 0);
  // a strongly deformed state: sheared, compressed and folded elements have negative curvature
  const Eigen::VectorXd x = jitter(mesh.rest_positions(), 0.3, 21);
  const Eigen::MatrixXd hp = -Eigen::MatrixXd(
      evaluate_forces(mesh, test_material(), x, zero, g, Jacobians::PROJECTED).dfdx);
  const Eigen::MatrixXd he =
      -Eigen::MatrixXd(evaluate_forces(mesh, test_material(), x, zero, g, Jacobians::EXACT).dfdx);
  const double scale = he.cwiseAbs().maxCoeff();
  const Eigen::VectorXd ep = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(hp).eigenvalues();
  const Eigen::VectorXd ee = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(he).eigenvalues();
  ASSERT_LT(ee.minCoeff(), -1e-3 * scale) << "the exact Hessian is PSD here: the test is vacuous";
  EXPECT_GT(ep.minCoeff(), -1e-12 * scale);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(hp - he).eigenvalues().minCoeff(),
            -1e-12 * scale);
  for (int d = 0; d < 3; ++d) {  // a rigid translation along d is in the null space
    Eigen::VectorXd t = zero;
    for (int i = 0; i < mesh.num_nodes(); ++i) t[3 * i + d] = 1;
    EXPECT_LT((hp * t).cwiseAbs().maxCoeff(), 1e-12 * scale * mesh.num_nodes());
  }
  // uniform tension (the flat sheet dilated by 10 %, unsheared): every element's exact
  // Hessian is PSD, and the projection leaves it as it is
  const Eigen::VectorXd xs = 1.1 * mesh.rest_positions();
  const Eigen::MatrixXd hs_p = -Eigen::MatrixXd(
      evaluate_forces(mesh, test_material(), xs, zero, g, Jacobians::PROJECTED).dfdx);
  const Eigen::MatrixXd hs_e =
      -Eigen::MatrixXd(evaluate_forces(mesh, test_material(), xs, zero, g, Jacobians::EXACT).dfdx);
  EXPECT_LT((hs_p - hs_e).cwiseAbs().maxCoeff(), 1e-10 * hs_e.cwiseAbs().maxCoeff());
}

TEST(SheetAssembly, RestMeshHasZeroEnergyAndForce) {
  const SheetMesh mesh = small_mesh();
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(mesh.num_dofs());
  const SheetForces f = evaluate_forces(mesh, test_material(), mesh.rest_positions(), zero,
                                        Eigen::Vector3d::Zero(), Jacobians::PSD);
  EXPECT_NEAR(f.elastic_energy, 0.0, 1e-25);
  EXPECT_LT(f.force.cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(mesh.hinges.size(), 3u + 4u + 6u);  // interior rows, columns, diagonals
}

TEST(SheetMeshes, RectangleHasTheExpectedTopologyAndMass) {
  const SheetMesh mesh = make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d(2, 0, 0),
                                        Eigen::Vector3d(0, 3, 0), 4.0, 3.0, 5, 4, 0.02);
  EXPECT_EQ(mesh.num_nodes(), 20);
  EXPECT_EQ(mesh.triangles.size(), 2u * 4 * 3);
  // interior edges: horizontal (nu−1)(nv−2) + vertical (nu−2)(nv−1) + one diagonal per quad
  EXPECT_EQ(mesh.hinges.size(), 4u * 2 + 3u * 3 + 4u * 3);
  EXPECT_NEAR(mesh.mass.sum(), 0.02 * 4 * 3, 1e-14);
  double area = 0;
  for (double a : mesh.area) area += a;
  EXPECT_NEAR(area, 12.0, 1e-12);
  EXPECT_TRUE(mesh.rest.col(grid_node(mesh, 4, 3)).isApprox(Eigen::Vector3d(4, 3, 0)));
  for (const SheetHinge& h : mesh.hinges) EXPECT_NEAR(h.rest_angle, 0.0, 1e-12);
  // the diagonals alternate: as many of each orientation (±1)
  int up = 0, down = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector2d a = mesh.uv.col(t[0]), c = mesh.uv.col(t[2]);
    (c - a).x() * (c - a).y() > 0 ? ++up : ++down;
  }
  EXPECT_GT(up, 0);
  EXPECT_GT(down, 0);
}

TEST(SheetMeshes, BadInputThrowsNamingTheParameter) {
  const Eigen::Vector3d o = Eigen::Vector3d::Zero(), ex = Eigen::Vector3d::UnitX(),
                        ey = Eigen::Vector3d::UnitY();
  auto expect_throw = [](const std::function<void()>& f, const std::string& word) {
    try {
      f();
      ADD_FAILURE() << "no exception for bad " << word;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  expect_throw([&] { make_rectangle(o, ex, ey, 0.0, 1.0, 3, 3); }, "width");
  expect_throw([&] { make_rectangle(o, ex, ey, 1.0, -1.0, 3, 3); }, "height");
  expect_throw([&] { make_rectangle(o, ex, ey, 1.0, 1.0, 1, 3); }, "nu");
  expect_throw([&] { make_rectangle(o, ex, ey, 1.0, 1.0, 3, 1); }, "nv");
  expect_throw([&] { make_rectangle(o, ex, ex, 1.0, 1.0, 3, 3); }, "parallel");
  expect_throw([&] { make_rectangle(o, ex, ey, 1.0, 1.0, 3, 3, 0.0); }, "density");
  // a triangle with material area but none in 3-D: its bend has no rest normal
  {
    Eigen::Matrix3Xd rest(3, 4);
    rest << 0, 1, 0, 0.5, 0, 0, 1, 0.5, 0, 0, 0, 0;  // node 3 halfway between nodes 1 and 2
    Eigen::Matrix2Xd uv(2, 4);
    uv << 0, 1, 0, 1, 0, 0, 1, 1;
    expect_throw([&] { make_sheet_mesh(rest, uv, {{0, 1, 2}, {1, 3, 2}}); }, "has no area");
  }
  const SheetMesh mesh = make_rectangle(o, ex, ey, 1.0, 1.0, 3, 3);
  expect_throw([&] { evaluate_forces(mesh, {}, Eigen::VectorXd(5), Eigen::VectorXd(27)); },
               "positions");
}

}  // namespace
}  // namespace knit::sheet
