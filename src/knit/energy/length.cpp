#include "knit/energy/length.hpp"

#include <cmath>

namespace knit {

namespace {
constexpr double SPEED_EPS = 1e-24;  // regularises |y'| at y' = 0 (cm² per parameter²)
}

double length_kernel(const Vector12d& x, double rest_length, double k_len,
                     const QuadratureTable& quad, Vector12d* grad) {
  double e = 0;
  const double inv_l = 1.0 / rest_length;
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector3d d1 = combine(x, quad.db[k]);
    const double speed = std::sqrt(d1.squaredNorm() + SPEED_EPS);
    const double r = 1.0 - speed * inv_l;
    e += quad.w[k] * r * r;
    if (grad) scatter(*grad, quad.db[k], (-2.0 * k_len * quad.w[k] * r * inv_l / speed) * d1);
  }
  return k_len * e;
}

lanes::VecD length_kernel_lanes(const lanes::VecD x[12], lanes::VecD rest_length, double k_len,
                                const QuadratureTable& quad, lanes::VecD grad[12]) {
  using lanes::VecD;
  for (int c = 0; c < 12; ++c) grad[c] = VecD{};
  VecD e{};
  const VecD inv_l = 1.0 / rest_length;
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector4d& db = quad.db[k];
    VecD d1[3];
    for (int c = 0; c < 3; ++c)
      d1[c] = db[0] * x[c] + db[1] * x[3 + c] + db[2] * x[6 + c] + db[3] * x[9 + c];
    const VecD speed = lanes::sqrt(d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2] + SPEED_EPS);
    const VecD r = 1.0 - speed * inv_l;
    e += quad.w[k] * r * r;
    const VecD coef = -2.0 * k_len * quad.w[k] * r * inv_l / speed;
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) grad[3 * a + c] += db[a] * (coef * d1[c]);
  }
  return k_len * e;
}

double LengthEnergy::add_force(const Model& model, const Eigen::VectorXd& q,
                               const Eigen::VectorXd& v, double time, Eigen::VectorXd& force) {
  const double k = model.params.material.k_len;
  // four segments per call of the lane kernel (tested against length_kernel)
  const double e =
      m_acc.run_lanes(model, q, [&](const lanes::VecD* x, const int* seg, lanes::VecD* g) {
        lanes::VecD rest;
        for (int l = 0; l < lanes::LANES; ++l) rest[l] = model.rest_length[seg[l]];
        return length_kernel_lanes(x, rest, k, model.quad, g);
      });
  m_acc.gather(model, force, -1.0);
  return e;
}

}  // namespace knit
