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

lanes::VecD bending_kernel_lanes(const lanes::VecD x[12], lanes::VecD rest_length, double k_bend,
                                 const QuadratureTable& quad, lanes::VecD grad[12]) {
  using lanes::VecD;
  for (int c = 0; c < 12; ++c) grad[c] = VecD{};
  VecD e{};
  const VecD scale = k_bend * rest_length;
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector4d& db = quad.db[k];
    const Eigen::Vector4d& ddb = quad.ddb[k];
    VecD d1[3], d2[3];
    for (int c = 0; c < 3; ++c) {
      d1[c] = db[0] * x[c] + db[1] * x[3 + c] + db[2] * x[6 + c] + db[3] * x[9 + c];
      d2[c] = ddb[0] * x[c] + ddb[1] * x[3 + c] + ddb[2] * x[6 + c] + ddb[3] * x[9 + c];
    }
    const VecD cr[3] = {d1[1] * d2[2] - d1[2] * d2[1], d1[2] * d2[0] - d1[0] * d2[2],
                        d1[0] * d2[1] - d1[1] * d2[0]};
    const VecD s = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2] + BEND_EPS;
    const VecD inv_s3 = 1.0 / (s * s * s);
    const VecD cc = cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2];
    e += quad.w[k] * cc * inv_s3;
    const VecD wk = scale * quad.w[k];
    // ∂κ²/∂y' = 2 (y''×c)/s³ − 6 (c·c) y'/s⁴,   ∂κ²/∂y'' = 2 (c×y')/s³
    const VecD two_inv_s3 = 2.0 * inv_s3;
    const VecD six_cc = 6.0 * cc * inv_s3 / s;
    const VecD d2xc[3] = {d2[1] * cr[2] - d2[2] * cr[1], d2[2] * cr[0] - d2[0] * cr[2],
                          d2[0] * cr[1] - d2[1] * cr[0]};
    const VecD cxd1[3] = {cr[1] * d1[2] - cr[2] * d1[1], cr[2] * d1[0] - cr[0] * d1[2],
                          cr[0] * d1[1] - cr[1] * d1[0]};
    VecD g1[3], g2[3];
    for (int c = 0; c < 3; ++c) {
      g1[c] = wk * (two_inv_s3 * d2xc[c] - six_cc * d1[c]);
      g2[c] = wk * (two_inv_s3 * cxd1[c]);
    }
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) grad[3 * a + c] += db[a] * g1[c];
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) grad[3 * a + c] += ddb[a] * g2[c];
  }
  return scale * e;
}

double BendingEnergy::add_force(const Model& model, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& v, double time, Eigen::VectorXd& force) {
  const double k = model.params.material.k_bend;
  // four segments per call of the lane kernel (tested against bending_kernel)
  const double e =
      m_acc.run_lanes(model, q, [&](const lanes::VecD* x, const int* seg, lanes::VecD* g) {
        lanes::VecD rest;
        for (int l = 0; l < lanes::LANES; ++l) rest[l] = model.rest_length[seg[l]];
        return bending_kernel_lanes(x, rest, k, model.quad, g);
      });
  m_acc.gather(model, force, -1.0);
  return e;
}

}  // namespace knit
