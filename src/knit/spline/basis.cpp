#include "knit/spline/basis.hpp"

#include <stdexcept>
#include <string>

namespace knit {

Eigen::Vector4d bspline_basis(double t) {
  const double s = 1.0 - t, t2 = t * t, t3 = t2 * t;
  return {s * s * s / 6.0, (3 * t3 - 6 * t2 + 4) / 6.0, (-3 * t3 + 3 * t2 + 3 * t + 1) / 6.0,
          t3 / 6.0};
}

Eigen::Vector4d bspline_basis_d1(double t) {
  const double s = 1.0 - t;
  return {-0.5 * s * s, (9 * t * t - 12 * t) / 6.0, (-9 * t * t + 6 * t + 3) / 6.0, 0.5 * t * t};
}

Eigen::Vector4d bspline_basis_d2(double t) {
  return {1.0 - t, 3 * t - 2, -3 * t + 1, t};
}

QuadratureTable make_table(std::vector<double> t, std::vector<double> w) {
  QuadratureTable q;
  q.t = std::move(t);
  q.w = std::move(w);
  for (double tk : q.t) {
    q.b.push_back(bspline_basis(tk));
    q.db.push_back(bspline_basis_d1(tk));
    q.ddb.push_back(bspline_basis_d2(tk));
  }
  return q;
}

QuadratureTable simpson_table(int points) {
  if (points < 3 || points % 2 == 0)
    throw std::invalid_argument("Simpson quadrature needs an odd number of points >= 3, got " +
                                std::to_string(points));
  const int n = points - 1;
  const double hstep = 1.0 / n;
  std::vector<double> t(points), w(points);
  for (int k = 0; k < points; ++k) {
    t[k] = k * hstep;
    w[k] = hstep / 3.0 * ((k == 0 || k == n) ? 1.0 : (k % 2 == 1 ? 4.0 : 2.0));
  }
  return make_table(std::move(t), std::move(w));
}

QuadratureTable midpoint_table(int points) {
  if (points < 1)
    throw std::invalid_argument("midpoint quadrature needs at least 1 point, got " +
                                std::to_string(points));
  std::vector<double> t(points), w(points, 1.0 / points);
  for (int k = 0; k < points; ++k) t[k] = (k + 0.5) / points;
  return make_table(std::move(t), std::move(w));
}

}  // namespace knit
