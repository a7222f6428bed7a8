#include "knit/energy/length.hpp"

#include <cmath>

#include "knit/energy/segment_kernel.hpp"

namespace knit {

namespace {
constexpr double SPEED_EPS = 1e-24;  // regularises |y'| at y' = 0 (cm² per parameter²)
}

template <class T>
T length_kernel_t(const T x[12], T rest_length, double k_len, const QuadratureTable& quad,
                  T* grad) {
  if (grad)
    for (int c = 0; c < 12; ++c) grad[c] = T{};
  T e{};
  const T inv_l = 1.0 / rest_length;
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector4d& db = quad.db[k];
    T d1[3];  // y'
    for (int c = 0; c < 3; ++c)
      d1[c] = db[0] * x[c] + db[1] * x[3 + c] + db[2] * x[6 + c] + db[3] * x[9 + c];
    const T speed = lanes::sqrt(d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2] + SPEED_EPS);
    const T r = 1.0 - speed * inv_l;  // E = k_len Σ w (1 − |y'|/ℓ)²
    e += quad.w[k] * r * r;
    if (!grad) continue;
    const T coef = -2.0 * k_len * quad.w[k] * r * inv_l / speed;
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) grad[3 * a + c] += db[a] * (coef * d1[c]);
  }
  return k_len * e;
}

template double length_kernel_t<double>(const double[12], double, double, const QuadratureTable&,
                                        double*);
template lanes::VecD length_kernel_t<lanes::VecD>(const lanes::VecD[12], lanes::VecD, double,
                                                  const QuadratureTable&, lanes::VecD*);

double length_kernel(const Vector12d& x, double rest_length, double k_len,
                     const QuadratureTable& quad, Vector12d* grad) {
  return on_one_segment(
      [&](const double* xs, double* g) {
        return length_kernel_t<double>(xs, rest_length, k_len, quad, g);
      },
      x, grad);
}

lanes::VecD length_kernel_lanes(const lanes::VecD x[12], lanes::VecD rest_length, double k_len,
                                const QuadratureTable& quad, lanes::VecD grad[12]) {
  return length_kernel_t<lanes::VecD>(x, rest_length, k_len, quad, grad);
}

Matrix12d length_hessian(const Vector12d& x, double rest_length, double k_len,
                         const QuadratureTable& quad, LengthHessian kind) {
  // per quadrature point the 3×3 block is A = c u uᵀ + β I (c = α − β, α = 2 k w / ℓ²,
  // β = −2 k w g / (ℓ |y'|)); block (a, b) of H is Σ_k B_a' B_b' A_k. Summed over the ten
  // pairs a ≤ b and the six entries of the symmetric u uᵀ, then mirrored.
  constexpr int XX = 0, XY = 1, XZ = 2, YY = 3, YZ = 4, ZZ = 5;
  double outer[10][6] = {}, iso[10] = {};
  const double inv_l = 1.0 / rest_length;
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector4d& db = quad.db[k];
    const Eigen::Vector3d d1 = combine(x, db);
    const double speed = std::sqrt(d1.squaredNorm() + SPEED_EPS);
    const double g = 1.0 - speed * inv_l;
    const double transverse = kind == LengthHessian::EXACT ? g : std::min(g, 0.0);
    const double alpha = 2.0 * k_len * quad.w[k] * inv_l * inv_l;
    const double beta = -2.0 * k_len * quad.w[k] * transverse * inv_l / speed;
    const double c = (alpha - beta) / (speed * speed);  // times d1 d1ᵀ = |y'|² u uᵀ
    const double m[6] = {c * d1.x() * d1.x(), c * d1.x() * d1.y(), c * d1.x() * d1.z(),
                         c * d1.y() * d1.y(), c * d1.y() * d1.z(), c * d1.z() * d1.z()};
    int pair = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a; b < 4; ++b, ++pair) {
        const double s = db[a] * db[b];
        for (int e = 0; e < 6; ++e) outer[pair][e] += s * m[e];
        iso[pair] += s * beta;
      }
  }
  Matrix12d h;
  int pair = 0;
  for (int a = 0; a < 4; ++a)
    for (int b = a; b < 4; ++b, ++pair) {
      const double* o = outer[pair];
      Eigen::Matrix3d block;
      block << o[XX] + iso[pair], o[XY], o[XZ], o[XY], o[YY] + iso[pair], o[YZ], o[XZ], o[YZ],
          o[ZZ] + iso[pair];
      h.block<3, 3>(3 * a, 3 * b) = block;
      if (b != a) h.block<3, 3>(3 * b, 3 * a) = block;
    }
  return h;
}

void LengthEnergy::segment_stiffness(const Model& model, const Eigen::VectorXd& q,
                                     std::vector<Matrix12d>& blocks) {
  const double k = model.params.material.k_len;
  segment_blocks(model, q, blocks, [&](const Vector12d& x, double rest) {
    return length_hessian(x, rest, k, model.quad, LengthHessian::PROJECTED);
  });
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
