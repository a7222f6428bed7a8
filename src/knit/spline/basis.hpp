#pragma once
// Uniform cubic B-spline basis (MODEL.md §1) and quadrature tables that hold the basis
// values and derivatives at fixed abscissae, computed once.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace knit {

using Vector12d = Eigen::Matrix<double, 12, 1>;
using Matrix12d = Eigen::Matrix<double, 12, 12>;

/// B_0..B_3 of a segment at parameter t ∈ [0,1].
Eigen::Vector4d bspline_basis(double t);
/// dB_a/dt.
Eigen::Vector4d bspline_basis_d1(double t);
/// d²B_a/dt².
Eigen::Vector4d bspline_basis_d2(double t);

/// A quadrature rule on [0,1] with the basis tabulated at its abscissae.
/// Σ w_k g(t_k) ≈ ∫₀¹ g(t) dt.
struct QuadratureTable {
  std::vector<double> t;
  std::vector<double> w;
  std::vector<Eigen::Vector4d> b;    ///< B_a(t_k)
  std::vector<Eigen::Vector4d> db;   ///< B_a'(t_k)
  std::vector<Eigen::Vector4d> ddb;  ///< B_a''(t_k)
  int size() const { return static_cast<int>(t.size()); }
};

/// Composite Simpson's rule with `points` abscissae (odd, ≥ 3), ends included.
QuadratureTable simpson_table(int points);
/// Midpoint rule: `points` cells of width 1/points, abscissae at cell centres.
QuadratureTable midpoint_table(int points);
/// Tabulates the basis at arbitrary abscissae with the given weights.
QuadratureTable make_table(std::vector<double> t, std::vector<double> w);

/// The 4 control points of a segment as one 12-vector (x0 y0 z0 x1 …).
inline Vector12d gather_segment(const Eigen::VectorXd& q, int first_cp) {
  return q.segment<12>(3 * first_cp);
}

/// Σ_a c_a x_a for a 12-vector of control points and 4 coefficients.
inline Eigen::Vector3d combine(const Vector12d& x, const Eigen::Vector4d& c) {
  return c[0] * x.segment<3>(0) + c[1] * x.segment<3>(3) + c[2] * x.segment<3>(6) +
         c[3] * x.segment<3>(9);
}

/// Adds c_a g to the 3 entries of control point a in a 12-vector (the transpose of combine).
inline void scatter(Vector12d& out, const Eigen::Vector4d& c, const Eigen::Vector3d& g) {
  for (int a = 0; a < 4; ++a) out.segment<3>(3 * a) += c[a] * g;
}

}  // namespace knit
