#include "knit/energy/bending.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "knit/energy/segment_kernel.hpp"

namespace knit {

namespace {
constexpr double BEND_EPS = 1e-14;  // cm² per unit parameter², far below any real |y'|²
}

template <class T>
T bending_kernel_t(const T x[12], T rest_length, double k_bend, const QuadratureTable& quad,
                   T* grad) {
  if (grad)
    for (int c = 0; c < 12; ++c) grad[c] = T{};
  T e{};
  const T scale = k_bend * rest_length;
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector4d& db = quad.db[k];
    const Eigen::Vector4d& ddb = quad.ddb[k];
    T d1[3], d2[3];  // y', y''
    for (int c = 0; c < 3; ++c) {
      d1[c] = db[0] * x[c] + db[1] * x[3 + c] + db[2] * x[6 + c] + db[3] * x[9 + c];
      d2[c] = ddb[0] * x[c] + ddb[1] * x[3 + c] + ddb[2] * x[6 + c] + ddb[3] * x[9 + c];
    }
    const T cr[3] = {d1[1] * d2[2] - d1[2] * d2[1], d1[2] * d2[0] - d1[0] * d2[2],
                     d1[0] * d2[1] - d1[1] * d2[0]};  // c = y' × y''
    const T s = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2] + BEND_EPS;
    const T inv_s3 = 1.0 / (s * s * s);
    const T cc = cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2];
    e += quad.w[k] * cc * inv_s3;  // κ² = |c|² / s³
    if (!grad) continue;
    const T wk = scale * quad.w[k];
    // ∂κ²/∂y' = 2 (y''×c)/s³ − 6 (c·c) y'/s⁴,   ∂κ²/∂y'' = 2 (c×y')/s³
    const T two_inv_s3 = 2.0 * inv_s3;
    const T six_cc = 6.0 * cc * inv_s3 / s;
    const T d2xc[3] = {d2[1] * cr[2] - d2[2] * cr[1], d2[2] * cr[0] - d2[0] * cr[2],
                       d2[0] * cr[1] - d2[1] * cr[0]};
    const T cxd1[3] = {cr[1] * d1[2] - cr[2] * d1[1], cr[2] * d1[0] - cr[0] * d1[2],
                       cr[0] * d1[1] - cr[1] * d1[0]};
    T g1[3], g2[3];
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

template double bending_kernel_t<double>(const double[12], double, double, const QuadratureTable&,
                                         double*);
template lanes::VecD bending_kernel_t<lanes::VecD>(const lanes::VecD[12], lanes::VecD, double,
                                                   const QuadratureTable&, lanes::VecD*);

double bending_kernel(const Vector12d& x, double rest_length, double k_bend,
                      const QuadratureTable& quad, Vector12d* grad) {
  return on_one_segment(
      [&](const double* xs, double* g) {
        return bending_kernel_t<double>(xs, rest_length, k_bend, quad, g);
      },
      x, grad);
}

lanes::VecD bending_kernel_lanes(const lanes::VecD x[12], lanes::VecD rest_length, double k_bend,
                                 const QuadratureTable& quad, lanes::VecD grad[12]) {
  return bending_kernel_t<lanes::VecD>(x, rest_length, k_bend, quad, grad);
}

Matrix12d bending_hessian(const Vector12d& x, double rest_length, double k_bend,
                          const QuadratureTable& quad, BendingHessian kind) {
  const Eigen::Matrix3d eye = Eigen::Matrix3d::Identity();
  Matrix12d h = Matrix12d::Zero();
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector4d& db = quad.db[k];
    const Eigen::Vector4d& ddb = quad.ddb[k];
    Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();  // y', y''
    for (int i = 0; i < 4; ++i) {
      a += db[i] * x.segment<3>(3 * i);
      b += ddb[i] * x.segment<3>(3 * i);
    }
    // κ² = f(a, b) = C g with C = |a×b|², g = s⁻³, s = |a|² + ε
    const Eigen::Vector3d c = a.cross(b);
    const double cc = c.squaredNorm(), ab = a.dot(b);
    const double s = a.squaredNorm() + BEND_EPS, g = 1.0 / (s * s * s);
    const Eigen::Vector3d ca = 2.0 * b.cross(c), cb = 2.0 * c.cross(a);  // ∂C/∂a, ∂C/∂b
    const Eigen::Vector3d ga = (-6.0 * g / s) * a;                       // ∂g/∂a
    const Eigen::Matrix3d caa = 2.0 * b.squaredNorm() * eye - 2.0 * b * b.transpose();
    const Eigen::Matrix3d cbb = 2.0 * a.squaredNorm() * eye - 2.0 * a * a.transpose();
    const Eigen::Matrix3d cab = 4.0 * a * b.transpose() - 2.0 * b * a.transpose() - 2.0 * ab * eye;
    const Eigen::Matrix3d gaa = (-6.0 * g / s) * eye + (48.0 * g / (s * s)) * a * a.transpose();
    const Eigen::Matrix3d faa = g * caa + ca * ga.transpose() + ga * ca.transpose() + cc * gaa;
    const Eigen::Matrix3d fab = g * cab + ga * cb.transpose();  // ∂²f/∂a ∂b
    const Eigen::Matrix3d fbb = g * cbb;
    // block (i, j) += w [B_i' (B_j' faa + B_j'' fab) + B_i'' (B_j' fabᵀ + B_j'' fbb)],
    // the upper triangle of blocks here, the lower one mirrored below
    const double w = quad.w[k];
    Eigen::Matrix3d u[4], t[4];
    for (int j = 0; j < 4; ++j) {
      u[j] = w * (db[j] * faa + ddb[j] * fab);
      t[j] = w * (db[j] * fab.transpose() + ddb[j] * fbb);
    }
    for (int i = 0; i < 4; ++i)
      for (int j = i; j < 4; ++j) h.block<3, 3>(3 * i, 3 * j) += db[i] * u[j] + ddb[i] * t[j];
  }
  for (int i = 1; i < 4; ++i)
    for (int j = 0; j < i; ++j)
      h.block<3, 3>(3 * i, 3 * j) = h.block<3, 3>(3 * j, 3 * i).transpose();
  h *= k_bend * rest_length;
  if (kind == BendingHessian::EXACT) return h;
  // the nearest positive semidefinite matrix: negative eigenvalues set to zero. (On a
  // hanging 42×32 knit no block was semidefinite already, by an LDLT's pivots: a test
  // that skipped those would save nothing.) The energy does not change when the segment
  // moves as a whole, so H annihilates the three translations exactly: the eigensolver
  // works on the 9 coordinates across them (Q: an orthonormal basis of that complement,
  // the Helmert contrasts of the four control points per axis), 40 % of a 12×12's cost.
  static const Eigen::Matrix<double, 12, 9> q = [] {
    Eigen::Matrix<double, 4, 3> helmert;
    helmert << 1 / std::sqrt(2.0), 1 / std::sqrt(6.0), 1 / std::sqrt(12.0),  //
        -1 / std::sqrt(2.0), 1 / std::sqrt(6.0), 1 / std::sqrt(12.0),        //
        0, -2 / std::sqrt(6.0), 1 / std::sqrt(12.0),                         //
        0, 0, -3 / std::sqrt(12.0);
    Eigen::Matrix<double, 12, 9> m = Eigen::Matrix<double, 12, 9>::Zero();
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j)
        m.block<3, 3>(3 * i, 3 * j) = helmert(i, j) * Eigen::Matrix3d::Identity();
    return m;
  }();
  const Eigen::Matrix<double, 9, 9> h9 = q.transpose() * h * q;
  // (the solver reads one triangle: h9 needs no symmetrising)
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> eig(h9);
  const Eigen::Matrix<double, 12, 9> v = q * eig.eigenvectors();
  return v * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * v.transpose();
}

void BendingEnergy::segment_stiffness(const Model& model, const Eigen::VectorXd& q,
                                      std::vector<Matrix12d>& blocks) {
  const double k = model.params.material.k_bend;
  segment_blocks(model, q, blocks, [&](const Vector12d& x, double rest) {
    return bending_hessian(x, rest, k, model.quad, BendingHessian::PROJECTED);
  });
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
