#include "knit/objects/object.hpp"

#include <cmath>

namespace knit {

ObjectFrame::ObjectFrame(const SceneObject& o, double time) : m_shape(o.shape.get()) {
  const Keyframe pose = interpolate_keyframes(o.keyframes, time);
  m_origin = o.position + pose.translation;
  m_to_world = (pose.rotation * o.rotation).toRotationMatrix();
  m_to_local = m_to_world.transpose();
  keyframe_rates(o.keyframes, time, m_velocity, m_omega);
  m_lipschitz = m_shape->lipschitz();
}

void segment_ball(const Model& model, const Eigen::VectorXd& q, int segment,
                  Eigen::Vector3d& centre, double& radius) {
  const double* p = q.data() + 3 * model.seg_cp[segment];
  centre = 0.25 * (Eigen::Vector3d(p) + Eigen::Vector3d(p + 3) + Eigen::Vector3d(p + 6) +
                   Eigen::Vector3d(p + 9));
  double r2 = 0;
  for (int a = 0; a < 4; ++a)
    r2 = std::max(r2, (Eigen::Vector3d(p + 3 * a) - centre).squaredNorm());
  radius = std::sqrt(r2);
}

}  // namespace knit
