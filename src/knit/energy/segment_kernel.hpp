#pragma once
// A per-segment kernel written once over its number type (double for one segment,
// lanes::VecD for four side by side: bending_kernel_t, length_kernel_t), called on one
// segment held as Eigen vectors.
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

}  // namespace knit
