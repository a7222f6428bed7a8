#include "knit/objects/object_penalty.hpp"

#include <algorithm>

#include "knit/objects/object.hpp"

namespace knit {

ObjectPenalty::ObjectPenalty(const Model& model) {
  for (size_t k = 0; k < model.objects.size(); ++k)
    if (model.objects[k]->penalty) m_objects.push_back(static_cast<int>(k));
  m_last.resize(m_objects.size());
  m_seg_stats.resize(m_objects.size());
}

double ObjectPenalty::add_force(const Model& model, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& v, double time, Eigen::VectorXd& force) {
  if (m_objects.empty()) return 0;
  const double r = model.params.material.radius;
  const QuadratureTable& quad = model.quad;
  std::vector<ObjectFrame> frames;
  for (int k : m_objects) frames.emplace_back(*model.objects[k], time);
  for (auto& stats : m_seg_stats) stats.assign(model.num_seg(), ObjectContacts{});
  const double energy = m_acc.run(model, [&](int i, Vector12d& slot) {
    Eigen::Vector3d centre;
    double rho;
    segment_ball(model, q, i, centre, rho);
    const Vector12d x = gather_segment(q, model.seg_cp[i]);
    const Vector12d u = gather_segment(v, model.seg_cp[i]);
    const double len = model.rest_length[i];
    double e = 0;
    for (size_t o = 0; o < frames.size(); ++o) {
      const ObjectFrame& f = frames[o];
      if (f.ball_outside(centre, rho, r)) continue;
      const SceneObject& obj = *model.objects[m_objects[o]];
      ObjectContacts& st = m_seg_stats[o][i];
      for (int p = 0; p < quad.size(); ++p) {
        const Eigen::Vector3d y = combine(x, quad.b[p]);
        Eigen::Vector3d grad;
        const double phi = f.distance(y, &grad);
        if (!(phi < r)) continue;
        const double gap = phi - r;  // < 0
        const double wl = quad.w[p] * len;
        e += obj.stiffness * wl * gap * gap;
        Eigen::Vector3d g = 2 * obj.stiffness * wl * gap * grad;  // ∂E/∂y
        const double gn = grad.norm();
        if (obj.damping > 0 && gn > 0) {
          const Eigen::Vector3d n = grad / gn;
          const Eigen::Vector3d w = combine(u, quad.b[p]) - f.velocity(y);
          g += obj.damping * wl * n.dot(w) * n;
        }
        scatter(slot, quad.b[p], -g);
        st.push -= g;
        ++st.points;
        st.deepest = std::max(st.deepest, -gap);
      }
    }
    return e;
  });
  m_acc.gather(model, force, 1.0);
  for (size_t o = 0; o < m_objects.size(); ++o) {
    m_last[o] = ObjectContacts{};
    for (const ObjectContacts& st : m_seg_stats[o]) m_last[o].add(st);
  }
  return energy;
}

void ObjectPenalty::record(StepData& data) const {
  record_contacts(m_objects, m_last, 1.0, data);
}

}  // namespace knit
