#include "knit/constraints/glue.hpp"

#include "knit/constraints/point_rows.hpp"
#include "knit/model/step_data.hpp"

namespace knit {

void GlueGroup::jacobian_structure(const Model& model,
                                   std::vector<Eigen::Triplet<double>>& entries) const {
  add_point_rows(model, 0, m_glue.a, 1.0, entries);
  add_point_rows(model, 0, m_glue.b, -1.0, entries);  // shared control points are summed
}

void GlueGroup::evaluate(const Model& model, const Eigen::VectorXd& q, double time, double* c,
                         double*) const {
  Eigen::Map<Eigen::Vector3d> out(c);
  out =
      point_position(model, q, m_glue.a) - point_position(model, q, m_glue.b) - m_glue.offset(time);
}

Eigen::Vector3d GlueGroup::torque_point(const Model& model, const Eigen::VectorXd& q,
                                        double time) const {
  return point_position(model, q, m_glue.b);
}

void GlueGroup::finish_record(ConstraintRecord& record, double h) const {
  // ∂C/∂y(a) = I: the force on point a is −Λ/h²; the net force on the yarns is zero
  record.force = -record.multipliers.head<3>() / (h * h);
}

}  // namespace knit
