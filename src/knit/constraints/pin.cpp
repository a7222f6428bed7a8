#include "knit/constraints/pin.hpp"

#include "knit/constraints/point_rows.hpp"

namespace knit {

void PinGroup::jacobian_structure(const Model& model,
                                  std::vector<Eigen::Triplet<double>>& entries) const {
  add_point_rows(model, 0, m_pin.at, 1.0, entries);
}

void PinGroup::evaluate(const Model& model, const Eigen::VectorXd& q, double time, double* c,
                        double*) const {
  Eigen::Map<Eigen::Vector3d> out(c);
  out = point_position(model, q, m_pin.at) - m_pin.target(time);
}

}  // namespace knit
