#include "knit/energy/global_damping.hpp"

namespace knit {

double global_damping_kernel(const Vector12d& u, double k_global, Vector12d* grad) {
  constexpr double int_b[4] = {1.0 / 24, 11.0 / 24, 11.0 / 24, 1.0 / 24};  // ∫₀¹ B_a
  double d = 0;
  for (int a = 0; a < 4; ++a) {
    d += int_b[a] * u.segment<3>(3 * a).squaredNorm();
    if (grad) grad->segment<3>(3 * a) += (2.0 * k_global * int_b[a]) * u.segment<3>(3 * a);
  }
  return k_global * d;
}

double GlobalDamping::add_force(const Model& model, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& v, double time, Eigen::VectorXd& force) {
  const double k = model.params.material.k_global;
  if (k == 0) return 0;
  m_acc.run(model, [&](int i, Vector12d& g) {
    global_damping_kernel(gather_segment(v, model.seg_cp[i]), k, &g);
    return 0.0;
  });
  m_acc.gather(model, force, -1.0);
  return 0;
}

}  // namespace knit
