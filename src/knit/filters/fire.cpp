#include "knit/filters/fire.hpp"

#include <cmath>

namespace knit {

void FireFilter::apply(const Model& model, const Eigen::VectorXd& /*q*/, Eigen::VectorXd& v,
                       double /*time*/, double h) {
  m_saved = {m_has_prev, m_alpha, m_downhill, m_restarts};
  m_can_reject = true;
  if (m_has_prev) m_saved_prev.swap(m_prev);  // m_prev is written anew below
  if (!m_has_prev || m_saved_prev.size() != v.size()) {
    // the first step (or a state from elsewhere): nothing to compare with yet
    m_prev = v;
    m_has_prev = true;
    return;
  }
  double power = 0, vv = 0, aa = 0;
  for (int k = 0; k < model.num_cp(); ++k) {
    const double m = model.mass[k];
    const Eigen::Vector3d vk = v.segment<3>(3 * k);
    const Eigen::Vector3d ak = (vk - m_saved_prev.segment<3>(3 * k)) / h;
    power += m * ak.dot(vk);
    vv += m * vk.squaredNorm();
    aa += m * ak.squaredNorm();
  }
  if (power > 0) {
    if (aa > 0) {
      // v ← (1 − α) v + α (|v| / |a|) a, with a = (v − prev) / h
      const double c = m_alpha * std::sqrt(vv / aa) / h;
      v = (1 - m_alpha + c) * v - c * m_saved_prev;
    }
    if (++m_downhill > N_MIN) m_alpha *= F_ALPHA;
  } else {
    v.setZero();
    m_alpha = ALPHA_START;
    m_downhill = 0;
    ++m_restarts;
  }
  m_prev = v;
}

void FireFilter::reject_step() {
  if (!m_can_reject) return;  // once per apply
  m_can_reject = false;
  m_has_prev = m_saved.has_prev;
  m_alpha = m_saved.alpha;
  m_downhill = m_saved.downhill;
  m_restarts = m_saved.restarts;
  if (m_has_prev) m_prev.swap(m_saved_prev);
}

}  // namespace knit
