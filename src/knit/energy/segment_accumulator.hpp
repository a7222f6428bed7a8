#pragma once
// Deterministic parallel assembly of per-segment 12-vectors into a global vector: every
// segment writes its own slot, then every control point sums the ≤ 4 slots touching it.
// Results do not depend on the thread count (no atomics, fixed summation order).
#include <Eigen/Core>
#include <vector>

#include "knit/model/model.hpp"

namespace knit {

class SegmentAccumulator {
 public:
  /// Runs `kernel(segment, slot) -> double` for every segment in parallel; `slot` is a
  /// zeroed Vector12d the kernel fills. Returns Σ of the kernel's return values.
  template <class Kernel>
  double run(const Model& model, Kernel&& kernel);
  /// out[3k..3k+2] += scale · Σ_{segments i touching k} slot_i[control point k − seg_cp_i].
  void gather(const Model& model, Eigen::VectorXd& out, double scale) const;

 private:
  std::vector<Vector12d> m_slots;
  std::vector<double> m_values;
};

}  // namespace knit

#include <tbb/parallel_for.h>

namespace knit {

template <class Kernel>
double SegmentAccumulator::run(const Model& model, Kernel&& kernel) {
  const int n = model.num_seg();
  m_slots.resize(n);
  m_values.resize(n);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 64), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i < r.end(); ++i) {
      m_slots[i].setZero();
      m_values[i] = kernel(i, m_slots[i]);
    }
  });
  double sum = 0;
  for (double e : m_values) sum += e;
  return sum;
}

}  // namespace knit
