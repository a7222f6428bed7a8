// The plain pair kernels of contact_kernel.hpp against finite differences.
#include "knit/contact/contact_kernel.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <random>
#include <string>

namespace knit {
namespace {

// largest |entry| (a plain loop: GCC 12 warns falsely inside Eigen's AVX-512 max reduction)
template <class V>
double max_abs(const V& v) {
  double m = 0;
  for (Eigen::Index k = 0; k < v.size(); ++k) m = std::max(m, std::abs(v[k]));
  return m;
}

const QuadratureTable& quad10() {
  static const QuadratureTable q = midpoint_table(10);
  return q;
}

// straight segment along `dir` through `centre`: 4 equally spaced collinear control points
// `h` apart, so the segment runs from centre − h/2·dir to centre + h/2·dir (length h)
Vector12d straight(const Eigen::Vector3d& centre, const Eigen::Vector3d& dir, double h) {
  Vector12d x;
  for (int a = 0; a < 4; ++a) x.segment<3>(3 * a) = centre + (a - 1.5) * h * dir;
  return x;
}

// smallest point-pair distance ratio over the contact quadrature
double min_ratio(const Vector12d& xi, const Vector12d& xj, const Params& p) {
  double m = std::numeric_limits<double>::infinity();
  for (int a = 0; a < quad10().size(); ++a)
    for (int b = 0; b < quad10().size(); ++b)
      m = std::min(m, (combine(xj, quad10().b[b]) - combine(xi, quad10().b[a])).norm() /
                          (2 * p.material.radius));
  return m;
}

// two perpendicular straight segments, j above i along z, placed so that the closest
// point pair is exactly at d = target (the quadrature points need not meet at the crossing)
std::pair<Vector12d, Vector12d> crossing(double target, const Params& p, double h = 0.3) {
  const Vector12d xi = straight({0, 0, 0}, {1, 0, 0}, h);
  const Vector12d flat = straight({0.01, 0.02, 0}, {0, 1, 0}, h);
  double m2 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < quad10().size(); ++a)
    for (int b = 0; b < quad10().size(); ++b)
      m2 = std::min(m2, (combine(flat, quad10().b[b]) - combine(xi, quad10().b[a])).squaredNorm());
  const double dz = std::sqrt(std::pow(target * 2 * p.material.radius, 2) - m2);
  Vector12d xj = flat;
  for (int a = 0; a < 4; ++a) xj[3 * a + 2] += dz;
  return {xi, xj};
}

// two skew segments, bent at random by up to 0.04 cm, crossing at d ≈ 0.4–1
std::pair<Vector12d, Vector12d> curved_skew_pair(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.04, 0.04);
  Vector12d xi = straight({0, 0, 0}, {1, 0, 0}, 0.3);
  Vector12d xj = straight({0.02, 0, 0.15}, Eigen::Vector3d(1, 0.5, 0).normalized(), 0.3);
  for (int k = 0; k < 12; ++k) {
    xi[k] += u(rng);
    xj[k] += u(rng);
  }
  return {xi, xj};
}

// central differences of `energy` over the 24 coordinates of (xi, xj) against (gi, gj)
template <class F>
void expect_gradient_matches(F&& energy, const Vector12d& xi, const Vector12d& xj,
                             const Vector12d& gi, const Vector12d& gj, double h, double rtol,
                             double atol, const std::string& what) {
  Eigen::Matrix<double, 24, 1> x, g;
  x << xi, xj;
  g << gi, gj;
  const double scale = max_abs(g);
  for (int k = 0; k < 24; ++k) {
    Eigen::Matrix<double, 24, 1> xp = x, xm = x;
    xp[k] += h;
    xm[k] -= h;
    const double fd =
        (energy(xp.head<12>(), xp.tail<12>()) - energy(xm.head<12>(), xm.tail<12>())) / (2 * h);
    EXPECT_NEAR(g[k], fd, rtol * scale + atol)
        << what << ": entry " << k << " (" << (k < 12 ? "segment i" : "segment j")
        << ", control point " << (k % 12) / 3 << ", axis "
        << "xyz"[k % 3] << ")";
  }
}

void check_energy_gradient(const Vector12d& xi, const Vector12d& xj, const std::string& what) {
  const Params p;
  const double li = 0.3, lj = 0.35;
  Vector12d gi, gj;
  contact_pair_gradient(xi, xj, li, lj, p, quad10(), gi, gj);
  ASSERT_GT(gi.norm(), 0) << what << ": the gradient is zero, nothing to compare";
  ASSERT_GT(gj.norm(), 0) << what;
  auto energy = [&](const Vector12d& a, const Vector12d& b) {
    return contact_pair_energy(a, b, li, lj, p, quad10());
  };
  expect_gradient_matches(energy, xi, xj, gi, gj, 1e-7, 1e-6, 0.0, what);
}

TEST(ContactKernel, PotentialVanishesSmoothlyAtActivation) {
  EXPECT_EQ(contact_potential(1.0), 0.0);
  EXPECT_EQ(contact_potential_d1(1.0), 0.0);
  EXPECT_EQ(contact_potential(1.5), 0.0);
  EXPECT_NEAR(contact_potential(1 - 1e-4), 4e-8, 1e-11);  // f ≈ 4(1−d)² near d = 1
  EXPECT_NEAR(contact_potential(0.5), 2.25, 1e-15);
  for (double d : {0.1, 0.3, 0.7, 0.99}) {
    const double h = 1e-6;
    EXPECT_NEAR(contact_potential_d1(d),
                (contact_potential(d + h) - contact_potential(d - h)) / (2 * h),
                1e-6 * std::abs(contact_potential_d1(d)))
        << "d = " << d;
  }
}

TEST(ContactKernel, GradientJustInsideActivation) {
  const Params p;
  const auto [xi, xj] = crossing(0.999, p);
  ASSERT_NEAR(min_ratio(xi, xj, p), 0.999, 1e-12);
  check_energy_gradient(xi, xj, "crossing at d = 0.999");
}

TEST(ContactKernel, GradientCloseCrossing) {
  const Params p;
  const auto [xi, xj] = crossing(0.3, p);
  ASSERT_NEAR(min_ratio(xi, xj, p), 0.3, 1e-12);
  check_energy_gradient(xi, xj, "crossing at d = 0.3");
}

TEST(ContactKernel, GradientCurvedSegmentsManyContacts) {
  // bent, skewed segments with point pairs spread over 0.4 < d < 1
  const auto [xi, xj] = curved_skew_pair(3);
  const Params p;
  const ContactPairResult r =
      contact_pair_force(xi, xj, Vector12d::Zero(), Vector12d::Zero(), 0.3, 0.35, p, quad10());
  ASSERT_GT(r.point_pairs_in_contact, 20);
  ASSERT_LT(r.point_pairs_in_contact, 100);  // some pairs outside: the cut-off is crossed
  check_energy_gradient(xi, xj, "curved skew segments");
}

TEST(ContactKernel, ContactExactlyAtActivationDistance) {
  // the closest point pair at d = 1 exactly: E, f and f' vanish, and so does the gradient
  const Params p;
  const auto [xi, xj] = crossing(1.0, p);
  ASSERT_NEAR(min_ratio(xi, xj, p), 1.0, 1e-12);
  Vector12d gi, gj;
  const double e = contact_pair_gradient(xi, xj, 0.3, 0.3, p, quad10(), gi, gj);
  const double kl = p.material.k_contact * 0.3 * 0.3;
  EXPECT_LE(e, 1e-20 * kl);
  EXPECT_LE(gi.norm() + gj.norm(), 1e-8 * kl);
  // finite differences straddle the cut-off (f is C¹ there, f'' jumps)
  auto energy = [&](const Vector12d& a, const Vector12d& b) {
    return contact_pair_energy(a, b, 0.3, 0.3, p, quad10());
  };
  expect_gradient_matches(energy, xi, xj, gi, gj, 1e-7, 0.0, 1e-5 * kl, "at d = 1");
  // parallel segments exactly 2r apart: every aligned point pair sits at d = 1
  const Vector12d yi = straight({0, 0, 0}, {1, 0, 0}, 0.3);
  const Vector12d yj = straight({0, 0, 2 * p.material.radius}, {1, 0, 0}, 0.3);
  EXPECT_LE(contact_pair_gradient(yi, yj, 0.3, 0.3, p, quad10(), gi, gj), 1e-20 * kl);
  EXPECT_LE(gi.norm() + gj.norm(), 1e-6 * kl);
}

TEST(ContactKernel, DampingForceMatchesFiniteDifferences) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 10.0);
  const Params p;
  const auto [xi, xj] = crossing(0.6, p);
  Vector12d vi, vj;
  for (int k = 0; k < 12; ++k) {
    vi[k] = n(rng);
    vj[k] = n(rng);
  }
  Vector12d fi, fj;
  contact_pair_damping_force(xi, xj, vi, vj, 0.3, 0.35, p, quad10(), fi, fj);
  ASSERT_GT(fi.norm(), 0);
  // force = −∂D/∂v: compare −force with the differences of D
  // (the positions captured by name: clang before 16 refuses a structured binding in a lambda)
  auto damping = [&, &xi = xi, &xj = xj](const Vector12d& a, const Vector12d& b) {
    return contact_pair_damping(xi, xj, a, b, 0.3, 0.35, p, quad10());
  };
  expect_gradient_matches(damping, vi, vj, -fi, -fj, 1e-4, 1e-7, 0.0, "damping");
  // D is a non-negative quadratic form: vᵀF = −2D ≤ 0
  const double d = damping(vi, vj);
  EXPECT_GT(d, 0);
  EXPECT_NEAR(vi.dot(fi) + vj.dot(fj), -2 * d, 1e-12 * d);
}

TEST(ContactKernel, CombinedResultAgreesWithParts) {
  const Params p;
  const auto [xi, xj] = crossing(0.5, p);
  Vector12d vi = Vector12d::LinSpaced(-3, 4), vj = Vector12d::LinSpaced(2, -1);
  const ContactPairResult r = contact_pair_force(xi, xj, vi, vj, 0.3, 0.4, p, quad10());
  Vector12d gi, gj, di, dj;
  const double e = contact_pair_gradient(xi, xj, 0.3, 0.4, p, quad10(), gi, gj);
  contact_pair_damping_force(xi, xj, vi, vj, 0.3, 0.4, p, quad10(), di, dj);
  EXPECT_DOUBLE_EQ(r.energy, e);
  EXPECT_LE((r.force_i - (di - gi)).norm(), 1e-12 * gi.norm());
  EXPECT_LE((r.force_j - (dj - gj)).norm(), 1e-12 * gj.norm());
  EXPECT_NEAR(r.min_distance_ratio, 0.5, 1e-12);
  // equal and opposite: the pair forces sum to zero (partition of unity of the basis)
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (int a = 0; a < 4; ++a) total += r.force_i.segment<3>(3 * a) + r.force_j.segment<3>(3 * a);
  EXPECT_LE(total.norm(), 1e-10 * r.force_i.norm());
}

}  // namespace
}  // namespace knit

namespace knit {
namespace {

// The exact Hessian is the derivative of the gradient (central differences of
// contact_pair_gradient); the projected one is positive semidefinite, drops only the
// negative transverse part, and has the same normal stiffness: Δᵀ H Δ agrees along the
// contact normals; the mirrored one turns the transverse part's sign instead.
TEST(ContactKernel, HessianMatchesFiniteDifferencesOfTheGradient) {
  const auto [xi, xj] = curved_skew_pair(7);
  const Params p;
  const double li = 0.3, lj = 0.35;
  const Eigen::Matrix<double, 24, 24> exact =
      contact_pair_hessian(xi, xj, li, lj, p, quad10(), ContactHessian::EXACT);
  const Eigen::Matrix<double, 24, 24> projected =
      contact_pair_hessian(xi, xj, li, lj, p, quad10(), ContactHessian::PROJECTED);
  ASSERT_GT(max_abs(exact.reshaped()), 0.0);
  Eigen::Matrix<double, 24, 1> x;
  x << xi, xj;
  const double h = 1e-7;
  double worst = 0;
  for (int k = 0; k < 24; ++k) {
    Eigen::Matrix<double, 24, 1> xp = x, xm = x;
    xp[k] += h;
    xm[k] -= h;
    Vector12d gpi, gpj, gmi, gmj;
    contact_pair_gradient(xp.head<12>(), xp.tail<12>(), li, lj, p, quad10(), gpi, gpj);
    contact_pair_gradient(xm.head<12>(), xm.tail<12>(), li, lj, p, quad10(), gmi, gmj);
    Eigen::Matrix<double, 24, 1> col;
    col << (gpi - gmi) / (2 * h), (gpj - gmj) / (2 * h);
    worst = std::max(worst, max_abs(col - exact.col(k)));
  }
  EXPECT_LT(worst, 1e-6 * max_abs(exact.reshaped())) << "largest difference " << worst;
  EXPECT_LT(max_abs((exact - exact.transpose()).reshaped()), 1e-9 * max_abs(exact.reshaped()));
  // projected: symmetric positive semidefinite, and at least as stiff as the exact one
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 24, 24>> eig(projected);
  EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-9 * eig.eigenvalues().maxCoeff());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 24, 24>> eig_exact(exact);
  EXPECT_LT(eig_exact.eigenvalues().minCoeff(), 0.0) << "the exact Hessian has no negative part";
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 24, 24>> diff(projected - exact);
  EXPECT_GT(diff.eigenvalues().minCoeff(), -1e-9 * eig.eigenvalues().maxCoeff());
  // a rigid translation of both segments has no stiffness
  Eigen::Matrix<double, 24, 1> shift;
  for (int k = 0; k < 8; ++k) shift.segment<3>(3 * k) = Eigen::Vector3d(0.3, -0.2, 0.5);
  EXPECT_LT(max_abs(projected * shift), 1e-9 * max_abs(projected.reshaped()));
  // beyond the contact distance, none
  const Vector12d far = xj + Vector12d::Constant(5.0);
  EXPECT_EQ(
      max_abs(contact_pair_hessian(xi, far, li, lj, p, quad10(), ContactHessian::EXACT).reshaped()),
      0.0);
  // mirrored: the exact transverse part with its sign turned, so 2 × projected − exact;
  // positive semidefinite, stiffer than the projected one, and no stiffness for a
  // translation
  const Eigen::Matrix<double, 24, 24> mirrored =
      contact_pair_hessian(xi, xj, li, lj, p, quad10(), ContactHessian::MIRRORED);
  EXPECT_LT(max_abs((mirrored - (2 * projected - exact)).reshaped()),
            1e-12 * max_abs(exact.reshaped()));
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 24, 24>> eig_mirrored(mirrored);
  EXPECT_GT(eig_mirrored.eigenvalues().minCoeff(), -1e-9 * eig_mirrored.eigenvalues().maxCoeff());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 24, 24>> above(mirrored - projected);
  EXPECT_GT(above.eigenvalues().minCoeff(), -1e-9 * eig_mirrored.eigenvalues().maxCoeff());
  EXPECT_GT(above.eigenvalues().maxCoeff(), 0.0) << "the transverse part is missing";
  EXPECT_LT(max_abs(mirrored * shift), 1e-9 * max_abs(mirrored.reshaped()));
}

TEST(ContactKernel, SecondDerivativeOfThePotential) {
  for (double d : {0.1, 0.3, 0.7, 0.99}) {
    const double h = 1e-6;
    EXPECT_NEAR(contact_potential_d2(d),
                (contact_potential_d1(d + h) - contact_potential_d1(d - h)) / (2 * h),
                1e-6 * contact_potential_d2(d))
        << "d = " << d;
  }
  EXPECT_EQ(contact_potential_d2(1.0), 0.0);
}

}  // namespace
}  // namespace knit
