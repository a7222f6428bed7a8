#include "knit/energy/length.hpp"

#include <algorithm>
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

namespace {

// Σ over the quadrature points of length_hessian's 3×3 blocks, for one segment (T = double)
// or four side by side (T = lanes::VecD): per quadrature point the block is
// A = c u uᵀ + β I (c = α − β, α = 2 k w / ℓ², β = −2 k w g / (ℓ |y'|)), and block (a, b)
// of H is Σ_k B_a' B_b' A_k, summed here over the ten pairs a ≤ b as the six entries of the
// symmetric u uᵀ part (`outer`, XX XY XZ YY YZ ZZ) and the multiple of I (`iso`).
template <class T>
void length_hessian_sums(const T x[12], T rest_length, double k_len, const QuadratureTable& quad,
                         LengthHessian kind, T outer[10][6], T iso[10]) {
  for (int pair = 0; pair < 10; ++pair) {
    iso[pair] = T{};
    for (int e = 0; e < 6; ++e) outer[pair][e] = T{};
  }
  const T inv_l = 1.0 / rest_length;
  const T zero{};
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector4d& db = quad.db[k];
    T d1[3];  // y'
    for (int c = 0; c < 3; ++c)
      d1[c] = db[0] * x[c] + db[1] * x[3 + c] + db[2] * x[6 + c] + db[3] * x[9 + c];
    const T speed = lanes::sqrt(d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2] + SPEED_EPS);
    const T g = 1.0 - speed * inv_l;
    const T transverse = kind == LengthHessian::EXACT ? g : (zero < g ? zero : g);  // min(g, 0)
    const T alpha = 2.0 * k_len * quad.w[k] * inv_l * inv_l;
    const T beta = -2.0 * k_len * quad.w[k] * transverse * inv_l / speed;
    const T c = (alpha - beta) / (speed * speed);  // times d1 d1ᵀ = |y'|² u uᵀ
    const T m[6] = {c * d1[0] * d1[0], c * d1[0] * d1[1], c * d1[0] * d1[2],
                    c * d1[1] * d1[1], c * d1[1] * d1[2], c * d1[2] * d1[2]};
    int pair = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a; b < 4; ++b, ++pair) {
        const double s = db[a] * db[b];
        for (int e = 0; e < 6; ++e) outer[pair][e] += s * m[e];
        iso[pair] += s * beta;
      }
  }
}

// The 12×12 Hessian from the sums, its lower triangle of blocks mirrored.
Matrix12d length_hessian_from_sums(const double outer[10][6], const double iso[10]) {
  constexpr int XX = 0, XY = 1, XZ = 2, YY = 3, YZ = 4, ZZ = 5;
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

// Four segments' Hessians at once (out of line, so that each group's code is the same
// wherever it falls in a thread's range: see length_constraints in
// constraints/inextensibility.cpp).
[[gnu::noinline]] void length_hessian_lanes(const lanes::VecD x[12], lanes::VecD rest, double k_len,
                                            const QuadratureTable& quad, LengthHessian kind,
                                            lanes::VecD outer[10][6], lanes::VecD iso[10]) {
  length_hessian_sums<lanes::VecD>(x, rest, k_len, quad, kind, outer, iso);
}

}  // namespace

Matrix12d length_hessian(const Vector12d& x, double rest_length, double k_len,
                         const QuadratureTable& quad, LengthHessian kind) {
  double outer[10][6], iso[10];
  length_hessian_sums<double>(x.data(), rest_length, k_len, quad, kind, outer, iso);
  return length_hessian_from_sums(outer, iso);
}

void LengthEnergy::segment_stiffness(const Model& model, const Eigen::VectorXd& q,
                                     std::vector<Matrix12d>& blocks) {
  using lanes::LANES;
  using lanes::VecD;
  const double k = model.params.material.k_len;
  const int n = model.num_seg();
  blocks.resize(n);
  // four segments per call of the lane kernel (tested against length_hessian)
  const int groups = (n + LANES - 1) / LANES;
  tbb::parallel_for(tbb::blocked_range<int>(0, groups, 16), [&](const tbb::blocked_range<int>& r) {
    for (int group = r.begin(); group < r.end(); ++group) {
      VecD x[12], rest, outer[10][6], iso[10];
      for (int l = 0; l < LANES; ++l) {
        // a last partial group repeats its last segment in the spare lanes
        const int i = std::min(group * LANES + l, n - 1);
        const double* p = q.data() + 3 * model.seg_cp[i];
        for (int c = 0; c < 12; ++c) x[c][l] = p[c];
        rest[l] = model.rest_length[i];
      }
      length_hessian_lanes(x, rest, k, model.quad, LengthHessian::PROJECTED, outer, iso);
      for (int l = 0; l < LANES && group * LANES + l < n; ++l) {
        double o[10][6], s[10];
        for (int pair = 0; pair < 10; ++pair) {
          s[pair] = iso[pair][l];
          for (int e = 0; e < 6; ++e) o[pair][e] = outer[pair][e][l];
        }
        blocks[group * LANES + l] = length_hessian_from_sums(o, s);
      }
    }
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
