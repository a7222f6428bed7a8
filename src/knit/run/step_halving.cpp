#include "knit/run/step_halving.hpp"

#include <algorithm>
#include <cmath>

#include "knit/model/params.hpp"

namespace knit {

StepResult HalvingStepper::step(Simulator& sim, State& state, double h) {
  if (m_max == 0 && m_counts.level == 0) {
    StepResult res = sim.step(state, h);
    if (res.ok()) ++m_counts.substeps;
    return res;
  }
  const double t_end = state.time + h;
  bool failed = false;
  StepResult last;
  while (true) {
    const double left = t_end - state.time;
    if (left <= 1e-9 * h) break;
    const double sub = std::ldexp(h, -m_counts.level);
    // the substeps tile h exactly (powers of two); the last one ends at t_end
    const double len = left < 1.5 * sub ? left : sub;
    StepResult res = sim.step(state, len);
    if (res.ok()) {
      ++m_counts.substeps;
      last = std::move(res);
      continue;
    }
    if (m_counts.level >= m_max) {
      if (m_max > 0)
        res.message += " (the step was halved " + std::to_string(m_counts.level) +
                       (m_counts.level == 1 ? " time" : " times") + ", to " + short_number(sub) +
                       " s, and still failed)";
      return res;
    }
    ++m_counts.level;
    ++m_counts.retried;
    m_counts.deepest = std::max(m_counts.deepest, m_counts.level);
    failed = true;
  }
  if (failed) {
    m_counts.calm = 0;
  } else if (m_counts.level > 0 && m_calm_steps > 0 && ++m_counts.calm >= m_calm_steps) {
    --m_counts.level;
    m_counts.calm = 0;
  }
  return last;
}

}  // namespace knit
