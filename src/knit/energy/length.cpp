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

double LengthEnergy::add_force(const Model& model, const Eigen::VectorXd& q,
                               const Eigen::VectorXd& v, Eigen::VectorXd& force) {
  const double k = model.params.k_len;
  const double e = m_acc.run(model, [&](int i, Vector12d& g) {
    return length_kernel(gather_segment(q, model.seg_cp[i]), model.rest_length[i], k, model.quad,
                         &g);
  });
  m_acc.gather(model, force, -1.0);
  return e;
}

}  // namespace knit
