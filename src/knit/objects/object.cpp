#include "knit/objects/object.hpp"

#include <algorithm>
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

void record_contacts(const std::vector<int>& objects, const std::vector<ObjectContacts>& contacts,
                     double force_scale, StepData& data) {
  for (size_t k = 0; k < objects.size(); ++k) {
    ObjectRecord& rec = data.objects[objects[k]];
    rec.points_in_contact += contacts[k].points;
    rec.deepest_penetration = std::max(rec.deepest_penetration, contacts[k].deepest);
    rec.force += force_scale * contacts[k].push;
  }
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
