#pragma once
// A per-segment kernel written once over its number type (double for one segment,
// lanes::VecD for four side by side: bending_kernel_t, length_kernel_t), called on one
// segment held as Eigen vectors.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <vector>

#include "knit/model/model.hpp"
#include "knit/spline/basis.hpp"

namespace knit {

/// kernel(x, grad) on one segment's 12 coordinates; adds ∂E/∂x into *grad (when given) and
/// returns the energy. `kernel` overwrites the gradient it is given (or takes nullptr).
template <class Kernel>
double on_one_segment(Kernel&& kernel, const Vector12d& x, Vector12d* grad) {
  if (!grad) return kernel(x.data(), nullptr);
  Vector12d g;
  const double e = kernel(x.data(), g.data());
  *grad += g;
  return e;
}

/// blocks[i] = hessian(x_i, ℓ_i) for every segment i (its 12 control-point coordinates in
/// q and its rest length), in parallel: a term's segment_stiffness.
template <class Hessian>
void segment_blocks(const Model& model, const Eigen::VectorXd& q, std::vector<Matrix12d>& blocks,
                    Hessian&& hessian) {
  const int n = model.num_seg();
  blocks.resize(n);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 256), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i < r.end(); ++i)
      blocks[i] = hessian(Vector12d(q.segment<12>(3 * model.seg_cp[i])), model.rest_length[i]);
  });
}

}  // namespace knit
