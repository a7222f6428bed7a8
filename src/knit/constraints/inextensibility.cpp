#include "knit/constraints/inextensibility.hpp"

#include <cmath>

namespace knit {

double length_constraint(const Vector12d& x, double rest_length, const QuadratureTable& quad,
                         Vector12d* grad) {
  const double inv_l = 1.0 / rest_length;
  double len = 0;
  if (grad) grad->setZero();
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector3d d1 = combine(x, quad.db[k]);
    const double speed = std::sqrt(d1.squaredNorm() + 1e-24);
    len += quad.w[k] * speed;
    if (grad) scatter(*grad, quad.db[k], (-quad.w[k] * inv_l / speed) * d1);
  }
  return 1.0 - len * inv_l;
}

}  // namespace knit
