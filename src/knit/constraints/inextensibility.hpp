#pragma once
// Inextensibility constraint, one scalar per segment (MODEL.md §5.1, paper eq. 5):
//   C_i = 1 − (1/ℓ_i) ∫₀¹ |y_i'(t)| dt      (dimensionless)
#include "knit/spline/basis.hpp"

namespace knit {

/// C_i for control points `x`; writes ∂C_i/∂x into *grad (overwrites) when non-null.
double length_constraint(const Vector12d& x, double rest_length, const QuadratureTable& quad,
                         Vector12d* grad);

}  // namespace knit
