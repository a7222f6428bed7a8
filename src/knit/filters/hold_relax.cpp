#include "knit/filters/hold_relax.hpp"

#include <algorithm>
#include <stdexcept>

namespace knit {

HoldRelaxFilter::HoldRelaxFilter(std::vector<std::unique_ptr<VelocityFilter>> outside,
                                 std::vector<std::pair<double, double>> windows)
    : m_outside(std::move(outside)), m_windows(std::move(windows)) {
  for (size_t i = 0; i < m_windows.size(); ++i)
    if (!(m_windows[i].second > m_windows[i].first) ||
        (i > 0 && m_windows[i].first < m_windows[i - 1].second))
      throw std::invalid_argument("hold windows: expected ordered, disjoint [start, end] in s");
}

int HoldRelaxFilter::window_at(double time) const {
  constexpr double EPS = 1e-9;
  // the first window ending at or after `time`
  const auto it =
      std::lower_bound(m_windows.begin(), m_windows.end(), time - EPS,
                       [](const std::pair<double, double>& w, double t) { return w.second < t; });
  if (it == m_windows.end() || !(time > it->first + EPS)) return -1;
  return static_cast<int>(it - m_windows.begin());
}

void HoldRelaxFilter::begin_step(const StepData& start, const Eigen::VectorXd& q_start) {
  for (auto& f : m_outside) f->begin_step(start, q_start);
}

void HoldRelaxFilter::apply(const Model& model, const Eigen::VectorXd& q, Eigen::VectorXd& v,
                            double time, double h) {
  const int w = window_at(time);
  m_window_before = m_window;
  m_outside_last = w < 0;
  if (w < 0) {
    for (auto& f : m_outside) f->apply(model, q, v, time, h);
  } else {
    if (w != m_window) m_fire.reset();  // a new hold: a new relaxation
    m_fire.apply(model, q, v, time, h);
  }
  m_window = w;
}

bool HoldRelaxFilter::adjust_positions(const Model& model, Eigen::VectorXd& q) const {
  if (!m_outside_last) return false;
  bool moved = false;
  for (const auto& f : m_outside) moved = f->adjust_positions(model, q) || moved;
  return moved;
}

void HoldRelaxFilter::reject_step() {
  if (m_outside_last)
    for (auto& f : m_outside) f->reject_step();
  else
    m_fire.reject_step();
  m_window = m_window_before;
}

void HoldRelaxFilter::record(StepData& data) const {
  for (const auto& f : m_outside) f->record(data);
}

}  // namespace knit
