#pragma once
// Second-order forward-mode automatic differentiation for small kernels: a Jet carries a
// value with its gradient and Hessian with respect to N seeded variables. The bending
// condition's exact Hessian (bw_energy.cpp) is computed with it; it is exact up to
// round-off, not a finite difference. Internal to knit::sheet.
#include <Eigen/Core>
#include <cmath>

namespace knit::sheet::detail {

template <int N>
struct Jet {
  using Vec = Eigen::Matrix<double, N, 1>;
  using Mat = Eigen::Matrix<double, N, N>;
  double v = 0;
  Vec g = Vec::Zero();
  Mat h = Mat::Zero();

  /// The k-th independent variable with value x.
  static Jet variable(double x, int k) {
    Jet j;
    j.v = x;
    j.g[k] = 1;
    return j;
  }
};

// result of f(a) with f' = f1, f'' = f2
template <int N>
Jet<N> chain1(const Jet<N>& a, double f, double f1, double f2) {
  Jet<N> r;
  r.v = f;
  r.g = f1 * a.g;
  r.h = f1 * a.h + f2 * a.g * a.g.transpose();
  return r;
}

// result of f(a, b) with its first and second partial derivatives
template <int N>
Jet<N> chain2(const Jet<N>& a, const Jet<N>& b, double f, double fa, double fb, double faa,
              double fab, double fbb) {
  Jet<N> r;
  r.v = f;
  r.g = fa * a.g + fb * b.g;
  const typename Jet<N>::Mat ab = a.g * b.g.transpose();
  r.h = fa * a.h + fb * b.h + faa * a.g * a.g.transpose() + fbb * b.g * b.g.transpose() +
        fab * (ab + ab.transpose());
  return r;
}

template <int N>
Jet<N> operator+(const Jet<N>& a, const Jet<N>& b) {
  Jet<N> r;
  r.v = a.v + b.v;
  r.g = a.g + b.g;
  r.h = a.h + b.h;
  return r;
}

template <int N>
Jet<N> operator-(const Jet<N>& a, const Jet<N>& b) {
  Jet<N> r;
  r.v = a.v - b.v;
  r.g = a.g - b.g;
  r.h = a.h - b.h;
  return r;
}

template <int N>
Jet<N> operator*(const Jet<N>& a, const Jet<N>& b) {
  return chain2(a, b, a.v * b.v, b.v, a.v, 0.0, 1.0, 0.0);
}

// a Jet plus or times a constant
template <int N>
Jet<N> operator+(Jet<N> a, double b) {
  a.v += b;
  return a;
}

template <int N>
Jet<N> operator*(double a, Jet<N> b) {
  b.v *= a;
  b.g *= a;
  b.h *= a;
  return b;
}

template <int N>
Jet<N> sqrt(const Jet<N>& a) {
  const double s = std::sqrt(a.v);
  return chain1(a, s, 0.5 / s, -0.25 / (s * a.v));
}

// θ = atan2(y, x): ∂θ/∂y = x/r², ∂θ/∂x = −y/r², ∂²θ/∂y² = −2xy/r⁴, ∂²θ/∂x² = 2xy/r⁴,
// ∂²θ/∂y∂x = (y² − x²)/r⁴
template <int N>
Jet<N> atan2(const Jet<N>& y, const Jet<N>& x) {
  const double r2 = x.v * x.v + y.v * y.v, r4 = r2 * r2;
  return chain2(y, x, std::atan2(y.v, x.v), x.v / r2, -y.v / r2, -2 * x.v * y.v / r4,
                (y.v * y.v - x.v * x.v) / r4, 2 * x.v * y.v / r4);
}

}  // namespace knit::sheet::detail
