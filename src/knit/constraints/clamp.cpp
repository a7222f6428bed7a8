#include "knit/constraints/clamp.hpp"

#include "knit/constraints/point_rows.hpp"

namespace knit {

void ClampGroup::jacobian_structure(const Model& model,
                                    std::vector<Eigen::Triplet<double>>& entries) const {
  for (size_t k = 0; k < m_clamp.points.size(); ++k)
    add_point_rows(model, 3 * static_cast<int>(k), m_clamp.points[k], 1.0, entries);
}

void ClampGroup::evaluate(const Model& model, const Eigen::VectorXd& q, double time, double* c,
                          double*) const {
  const Keyframe pose = m_clamp.pose(time);
  const Eigen::Matrix3d r = pose.rotation.toRotationMatrix();
  const Eigen::Vector3d origin = m_clamp.centre + pose.translation;
  for (size_t k = 0; k < m_clamp.points.size(); ++k) {
    Eigen::Map<Eigen::Vector3d> out(c + 3 * k);
    out = point_position(model, q, m_clamp.points[k]) -
          (origin + r * (m_clamp.rest[k] - m_clamp.centre));
  }
}

}  // namespace knit
