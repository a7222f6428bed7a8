#include "knit/energy/bending.hpp"

namespace knit {

namespace {
constexpr double BEND_EPS = 1e-14;  // cm² per unit parameter², far below any real |y'|²
}

double bending_kernel(const Vector12d& x, double rest_length, double k_bend,
                      const QuadratureTable& quad, Vector12d* grad) {
  double e = 0;
  const double scale = k_bend * rest_length;
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector3d d1 = combine(x, quad.db[k]);
    const Eigen::Vector3d d2 = combine(x, quad.ddb[k]);
    const Eigen::Vector3d c = d1.cross(d2);
    const double s = d1.squaredNorm() + BEND_EPS;
    const double inv_s3 = 1.0 / (s * s * s);
    const double cc = c.squaredNorm();
    e += quad.w[k] * cc * inv_s3;
    if (grad) {
      const double wk = scale * quad.w[k];
      // ∂κ²/∂y' = 2 (y''×c)/s³ − 6 (c·c) y'/s⁴,   ∂κ²/∂y'' = 2 (c×y')/s³
      const Eigen::Vector3d g1 = 2.0 * inv_s3 * d2.cross(c) - 6.0 * cc * inv_s3 / s * d1;
      const Eigen::Vector3d g2 = 2.0 * inv_s3 * c.cross(d1);
      scatter(*grad, quad.db[k], wk * g1);
      scatter(*grad, quad.ddb[k], wk * g2);
    }
  }
  return scale * e;
}

double BendingEnergy::add_force(const Model& model, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& v, Eigen::VectorXd& force) {
  const double k = model.params.k_bend;
  const double e = m_acc.run(model, [&](int i, Vector12d& g) {
    return bending_kernel(gather_segment(q, model.seg_cp[i]), model.rest_length[i], k, model.quad,
                          &g);
  });
  m_acc.gather(model, force, -1.0);
  return e;
}

}  // namespace knit
