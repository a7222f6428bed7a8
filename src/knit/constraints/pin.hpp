#pragma once
// Pin: one yarn point held at a target moving linearly in time (Model's Pin),
//   C = y(s) − p(t)      (3 rows, cm).
// The force the pin exerts on the yarn over a step is −Λ/h² (dyn), Λ its multipliers.
#include "knit/constraints/group.hpp"
#include "knit/model/model.hpp"

namespace knit {

class PinGroup : public ConstraintGroup {
 public:
  PinGroup(std::string name, Pin pin) : ConstraintGroup(std::move(name)), m_pin(std::move(pin)) {}
  std::string_view kind() const override { return "pin"; }
  int rows() const override { return 3; }
  void jacobian_structure(const Model& model,
                          std::vector<Eigen::Triplet<double>>& entries) const override;
  void evaluate(const Model& model, const Eigen::VectorXd& q, double time, double* c,
                double* jacobian) const override;
  /// Torques about the pin's target.
  Eigen::Vector3d torque_point(const Model& model, const Eigen::VectorXd& q,
                               double time) const override {
    return m_pin.target(time);
  }
  const Pin& pin() const { return m_pin; }

 private:
  Pin m_pin;
};

}  // namespace knit
