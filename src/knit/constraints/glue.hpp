#pragma once
// Glue: two yarn points held together, with a gap that closes linearly in time (Model's
// Glue),  C = y(a) − y(b) − g(t)   (3 rows, cm).
// Its two points feel opposite forces; the reported force is the one on point a, −Λ/h²
// (dyn), and the torque is taken about point b.
#include "knit/constraints/group.hpp"
#include "knit/model/model.hpp"

namespace knit {

class GlueGroup : public ConstraintGroup {
 public:
  GlueGroup(std::string name, Glue glue)
      : ConstraintGroup(std::move(name)), m_glue(std::move(glue)) {}
  std::string_view kind() const override { return "glue"; }
  int rows() const override { return 3; }
  void jacobian_structure(const Model& model,
                          std::vector<Eigen::Triplet<double>>& entries) const override;
  void evaluate(const Model& model, const Eigen::VectorXd& q, double time, double* c,
                double* jacobian) const override;
  Eigen::Vector3d torque_point(const Model& model, const Eigen::VectorXd& q,
                               double time) const override;
  void finish_record(ConstraintRecord& record, double h) const override;
  const Glue& glue() const { return m_glue; }

 private:
  Glue m_glue;
};

}  // namespace knit
