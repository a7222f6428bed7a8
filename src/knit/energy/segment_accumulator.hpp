#pragma once
// Deterministic parallel assembly of per-segment 12-vectors into a global vector: every
// segment writes its own slot, then every control point sums the ≤ 4 slots touching it.
// Results do not depend on the thread count (no atomics, fixed summation order).
#include <Eigen/Core>
#include <vector>

#include "knit/energy/lanes.hpp"
#include "knit/model/model.hpp"

namespace knit {

class SegmentAccumulator {
 public:
  /// Runs `kernel(segment, slot) -> double` for every segment in parallel; `slot` is a
  /// zeroed Vector12d the kernel fills. Returns Σ of the kernel's return values.
  template <class Kernel>
  double run(const Model& model, Kernel&& kernel);
  /// Like run, lanes::LANES segments at a time (one per lane): `kernel(x, seg, grad) ->
  /// VecD` gets x[c] = coordinate c of the 12 control-point coordinates of each lane's
  /// segment, taken from q, and the segment indices seg[LANES]; it writes every lane's
  /// 12-vector into grad[12] and returns every lane's value. A last partial group repeats
  /// its last segment in the spare lanes, whose results are dropped.
  template <class LaneKernel>
  double run_lanes(const Model& model, const Eigen::VectorXd& q, LaneKernel&& kernel);
  /// Like run, filling this accumulator's slot and `second`'s in one pass:
  /// `kernel(segment, slot, second_slot) -> double`, both slots zeroed.
  template <class Kernel>
  double run2(const Model& model, SegmentAccumulator& second, Kernel&& kernel);
  /// out[3k..3k+2] += scale · Σ_{segments i touching k} slot_i[control point k − seg_cp_i].
  void gather(const Model& model, Eigen::VectorXd& out, double scale) const;

 private:
  std::vector<Vector12d> m_slots;
  std::vector<double> m_values;
};

}  // namespace knit

#include <tbb/parallel_for.h>

#include <algorithm>

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

template <class Kernel>
double SegmentAccumulator::run2(const Model& model, SegmentAccumulator& second, Kernel&& kernel) {
  const int n = model.num_seg();
  m_slots.resize(n);
  m_values.resize(n);
  second.m_slots.resize(n);
  second.m_values.assign(n, 0.0);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 64), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i < r.end(); ++i) {
      m_slots[i].setZero();
      second.m_slots[i].setZero();
      m_values[i] = kernel(i, m_slots[i], second.m_slots[i]);
    }
  });
  double sum = 0;
  for (double e : m_values) sum += e;
  return sum;
}

template <class LaneKernel>
double SegmentAccumulator::run_lanes(const Model& model, const Eigen::VectorXd& q,
                                     LaneKernel&& kernel) {
  using lanes::LANES;
  using lanes::VecD;
  const int n = model.num_seg();
  m_slots.resize(n);
  m_values.resize(n);
  const int groups = (n + LANES - 1) / LANES;
  tbb::parallel_for(tbb::blocked_range<int>(0, groups, 16), [&](const tbb::blocked_range<int>& r) {
    for (int group = r.begin(); group < r.end(); ++group) {
      int seg[LANES];
      VecD x[12], grad[12];
      for (int l = 0; l < LANES; ++l) {
        seg[l] = std::min(group * LANES + l, n - 1);
        const double* p = q.data() + 3 * model.seg_cp[seg[l]];
        for (int c = 0; c < 12; ++c) x[c][l] = p[c];
      }
      const VecD values = kernel(x, seg, grad);
      for (int l = 0; l < LANES && group * LANES + l < n; ++l) {
        Vector12d& slot = m_slots[seg[l]];
        for (int c = 0; c < 12; ++c) slot[c] = grad[c][l];
        m_values[seg[l]] = values[l];
      }
    }
  });
  double sum = 0;
  for (double e : m_values) sum += e;
  return sum;
}

}  // namespace knit
