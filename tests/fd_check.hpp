#pragma once
// Finite-difference checks shared by the derivative tests.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <functional>
#include <random>
#include <sstream>

namespace knit::test {

/// Central-difference gradient of f at x with step h.
inline Eigen::VectorXd fd_gradient(const std::function<double(const Eigen::VectorXd&)>& f,
                                   Eigen::VectorXd x, double h) {
  Eigen::VectorXd g(x.size());
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    const double x0 = x[k];
    x[k] = x0 + h;
    const double fp = f(x);
    x[k] = x0 - h;
    const double fm = f(x);
    x[k] = x0;
    g[k] = (fp - fm) / (2 * h);
  }
  return g;
}

/// Asserts that `analytic` matches the central difference of f: it must be non-zero,
/// and every entry must agree within rel·max|g| + abs. Failures name the entry.
inline void expect_gradient_matches(const std::function<double(const Eigen::VectorXd&)>& f,
                                    const Eigen::VectorXd& x, const Eigen::VectorXd& analytic,
                                    double h, double rel, const std::string& what) {
  const Eigen::VectorXd fd = fd_gradient(f, x, h);
  const double scale = std::max(fd.cwiseAbs().maxCoeff(), analytic.cwiseAbs().maxCoeff());
  ASSERT_GT(scale, 0.0) << what << ": gradient is zero; the check would be vacuous";
  for (Eigen::Index k = 0; k < x.size(); ++k)
    EXPECT_NEAR(analytic[k], fd[k], rel * scale)
        << what << ": entry " << k << " (control point " << k / 3 << ", coordinate "
        << "xyz"[k % 3] << ")";
}

/// Random perturbation of size `amount` in every coordinate.
inline Eigen::VectorXd jitter(const Eigen::VectorXd& x, double amount, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amount, amount);
  Eigen::VectorXd y = x;
  for (Eigen::Index k = 0; k < y.size(); ++k) y[k] += u(rng);
  return y;
}

}  // namespace knit::test
