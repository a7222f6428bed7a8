#include "knit/contact/contact_kernel.hpp"

#include <cmath>
#include <vector>

namespace knit {
namespace {

// which parts of the pair kernel to evaluate
struct Want {
  bool gradient = false;
  bool damping_force = false;
};

// the dense reference loop over all point pairs (a, b); fills `out` with E, the energy
// gradient (not negated) in grad_*, D in `damping` and −∂D/∂ẋ in damp_*
struct DenseOut {
  double energy = 0, damping = 0;
  Vector12d grad_i = Vector12d::Zero(), grad_j = Vector12d::Zero();
  Vector12d damp_i = Vector12d::Zero(), damp_j = Vector12d::Zero();
  int contacts = 0;
  double min_d = std::numeric_limits<double>::infinity();
};

DenseOut dense_pair(const Vector12d& xi, const Vector12d& xj, const Vector12d* vi,
                    const Vector12d* vj, double li, double lj, const Params& params,
                    const QuadratureTable& quad, Want want) {
  DenseOut out;
  const int n = quad.size();
  const double two_r = 2.0 * params.material.radius;
  const double kl = params.material.k_contact * li * lj;
  std::vector<Eigen::Vector3d> yi(n), yj(n), ui(n), uj(n);
  for (int a = 0; a < n; ++a) {
    yi[a] = combine(xi, quad.b[a]);
    yj[a] = combine(xj, quad.b[a]);
    if (vi) {
      ui[a] = combine(*vi, quad.b[a]);
      uj[a] = combine(*vj, quad.b[a]);
    }
  }
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const Eigen::Vector3d diff = yj[b] - yi[a];
      const double dist = diff.norm();
      const double d = dist / two_r;
      if (d < out.min_d) out.min_d = d;
      if (!(d < 1.0)) continue;
      ++out.contacts;
      const double ww = quad.w[a] * quad.w[b];
      out.energy += kl * ww * contact_potential(d);
      const Eigen::Vector3d nhat = diff / dist;
      if (want.gradient) {
        // ∂E/∂y_j(t_b) = k ℓℓ ww f'(d) n̂ / 2r, and the opposite on y_i(t_a)
        const Eigen::Vector3d g = (kl * ww * contact_potential_d1(d) / two_r) * nhat;
        scatter(out.grad_j, quad.b[b], g);
        scatter(out.grad_i, quad.b[a], -g);
      }
      if (vi) {
        const Eigen::Vector3d dv = uj[b] - ui[a];
        const double vn = nhat.dot(dv);
        const double lw = li * lj * ww;
        out.damping += lw * (params.material.k_dt * dv.squaredNorm() -
                             (params.material.k_dt - params.material.k_dn) * vn * vn);
        if (want.damping_force) {
          const Eigen::Vector3d fj =
              (-2.0 * lw) * (params.material.k_dt * dv -
                             (params.material.k_dt - params.material.k_dn) * vn * nhat);
          scatter(out.damp_j, quad.b[b], fj);
          scatter(out.damp_i, quad.b[a], -fj);
        }
      }
    }
  }
  return out;
}

}  // namespace

double contact_pair_energy(const Vector12d& xi, const Vector12d& xj, double li, double lj,
                           const Params& params, const QuadratureTable& quad) {
  return dense_pair(xi, xj, nullptr, nullptr, li, lj, params, quad, Want{}).energy;
}

double contact_pair_gradient(const Vector12d& xi, const Vector12d& xj, double li, double lj,
                             const Params& params, const QuadratureTable& quad, Vector12d& grad_i,
                             Vector12d& grad_j) {
  const DenseOut out =
      dense_pair(xi, xj, nullptr, nullptr, li, lj, params, quad, Want{.gradient = true});
  grad_i = out.grad_i;
  grad_j = out.grad_j;
  return out.energy;
}

Eigen::Matrix<double, 24, 24> contact_pair_hessian(const Vector12d& xi, const Vector12d& xj,
                                                   double li, double lj, const Params& params,
                                                   const QuadratureTable& quad,
                                                   ContactHessian kind) {
  Eigen::Matrix<double, 24, 24> hess = Eigen::Matrix<double, 24, 24>::Zero();
  const int n = quad.size();
  const double two_r = 2.0 * params.material.radius;
  const double kl = params.material.k_contact * li * lj;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const Eigen::Vector3d diff = combine(xj, quad.b[b]) - combine(xi, quad.b[a]);
      const double dist = diff.norm();
      const double d = dist / two_r;
      if (!(d < 1.0)) continue;
      const double c = kl * quad.w[a] * quad.w[b];
      const Eigen::Vector3d nhat = diff / dist;
      const Eigen::Matrix3d nn = nhat * nhat.transpose();
      Eigen::Matrix3d h = (c * contact_potential_d2(d) / (two_r * two_r)) * nn;
      const double transverse = c * contact_potential_d1(d) / (two_r * dist);
      if (kind == ContactHessian::EXACT)
        h += transverse * (Eigen::Matrix3d::Identity() - nn);
      else if (kind == ContactHessian::MIRRORED)
        h += std::abs(transverse) * (Eigen::Matrix3d::Identity() - nn);
      // J_p: −B_a(t_a) on x_i's control points, +B_b(t_b) on x_j's
      double coef[8];
      for (int k = 0; k < 4; ++k) {
        coef[k] = -quad.b[a][k];
        coef[4 + k] = quad.b[b][k];
      }
      for (int p = 0; p < 8; ++p)
        for (int q = 0; q < 8; ++q) hess.block<3, 3>(3 * p, 3 * q) += (coef[p] * coef[q]) * h;
    }
  return hess;
}

double contact_pair_damping(const Vector12d& xi, const Vector12d& xj, const Vector12d& vi,
                            const Vector12d& vj, double li, double lj, const Params& params,
                            const QuadratureTable& quad) {
  return dense_pair(xi, xj, &vi, &vj, li, lj, params, quad, Want{}).damping;
}

void contact_pair_damping_force(const Vector12d& xi, const Vector12d& xj, const Vector12d& vi,
                                const Vector12d& vj, double li, double lj, const Params& params,
                                const QuadratureTable& quad, Vector12d& force_i,
                                Vector12d& force_j) {
  const DenseOut out =
      dense_pair(xi, xj, &vi, &vj, li, lj, params, quad, Want{.damping_force = true});
  force_i = out.damp_i;
  force_j = out.damp_j;
}

ContactPairResult contact_pair_force(const Vector12d& xi, const Vector12d& xj, const Vector12d& vi,
                                     const Vector12d& vj, double li, double lj,
                                     const Params& params, const QuadratureTable& quad) {
  const DenseOut out = dense_pair(xi, xj, &vi, &vj, li, lj, params, quad,
                                  Want{.gradient = true, .damping_force = true});
  ContactPairResult r;
  r.energy = out.energy;
  r.force_i = out.damp_i - out.grad_i;
  r.force_j = out.damp_j - out.grad_j;
  r.point_pairs_in_contact = out.contacts;
  r.min_distance_ratio = out.min_d;
  return r;
}

}  // namespace knit
