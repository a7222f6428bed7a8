#include "knit/constraints/clamp.hpp"

#include "knit/constraints/point_rows.hpp"

namespace knit {

void ClampGroup::jacobian_structure(const Model& model,
                                    std::vector<Eigen::Triplet<double>>& entries) const {
  const int np = static_cast<int>(m_clamp.points.size());
  for (int k = 0; k < np; ++k) add_point_rows(model, 3 * k, m_clamp.points[k], 1.0, entries);
  for (size_t k = 0; k < m_clamp.control_points.size(); ++k)
    for (int c = 0; c < 3; ++c)
      entries.emplace_back(3 * (np + static_cast<int>(k)) + c, 3 * m_clamp.control_points[k] + c,
                           1.0);
}

void ClampGroup::evaluate(const Model& model, const Eigen::VectorXd& q, double time, double* c,
                          double*) const {
  const Keyframe pose = m_clamp.pose(time);
  const Eigen::Matrix3d r = pose.rotation.toRotationMatrix();
  const Eigen::Vector3d origin = m_clamp.centre + pose.translation;
  const size_t np = m_clamp.points.size();
  for (size_t k = 0; k < m_clamp.rest.size(); ++k) {
    Eigen::Map<Eigen::Vector3d> out(c + 3 * k);
    const Eigen::Vector3d y =
        k < np ? point_position(model, q, m_clamp.points[k])
               : Eigen::Vector3d(q.segment<3>(3 * m_clamp.control_points[k - np]));
    out = y - (origin + r * (m_clamp.rest[k] - m_clamp.centre));
  }
}

}  // namespace knit
