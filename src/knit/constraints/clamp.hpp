#pragma once
// Clamp: yarn points and control points held rigidly to a moving frame (Model's Clamp),
//   C_k = y(s_k) − [c + T(t) + R(t)(y_k⁰ − c)]      (3 rows per point, cm)
//   C_k = x_k − [c + T(t) + R(t)(x_k⁰ − c)]         (3 rows per control point)
// with y_k⁰ the point's position at time 0, c the points' centroid then, and T, R the
// frame's keyframed translation and rotation. The force the clamp exerts on the yarn over
// a step is Σ_k −Λ_k / h² (dyn); its torque is reported about the frame's current centre
// c + T(t).
#include "knit/constraints/group.hpp"
#include "knit/model/model.hpp"

namespace knit {

class ClampGroup : public ConstraintGroup {
 public:
  explicit ClampGroup(Clamp clamp) : ConstraintGroup(clamp.name), m_clamp(std::move(clamp)) {}
  std::string_view kind() const override { return "clamp"; }
  int rows() const override { return 3 * static_cast<int>(m_clamp.rest.size()); }
  void jacobian_structure(const Model& model,
                          std::vector<Eigen::Triplet<double>>& entries) const override;
  void evaluate(const Model& model, const Eigen::VectorXd& q, double time, double* c,
                double* jacobian) const override;
  Eigen::Vector3d torque_point(const Model& model, const Eigen::VectorXd& q,
                               double time) const override {
    return m_clamp.centre + m_clamp.pose(time).translation;
  }
  const Clamp& clamp() const { return m_clamp; }

 private:
  Clamp m_clamp;
};

}  // namespace knit
