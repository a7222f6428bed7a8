#include "knit/energy/gravity.hpp"

namespace knit {

double Gravity::add_force(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                          double time, Eigen::VectorXd& force) {
  const Eigen::Vector3d& g = model.params.gravity;
  if (g.isZero(0)) return 0;  // a relaxation's weightless knit: nothing to add
  for (int k = 0; k < model.num_cp(); ++k) force.segment<3>(3 * k) += model.mass[k] * g;
  return energy(model, q, time);
}

double Gravity::energy(const Model& model, const Eigen::VectorXd& q, double /*time*/) {
  const Eigen::Vector3d& g = model.params.gravity;
  if (g.isZero(0)) return 0;
  double e = 0;
  for (int k = 0; k < model.num_cp(); ++k) e -= model.mass[k] * g.dot(q.segment<3>(3 * k));
  return e;
}

}  // namespace knit
