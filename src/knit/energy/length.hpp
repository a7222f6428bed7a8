#pragma once
// Length energy (MODEL.md §3, paper eq. 6): keeps the parameterisation speed uniform so
// mass does not slide along the curve.
//   E_i = k_len ∫₀¹ (1 − |y_i'(t)| / ℓ_i)² dt
// Units: k_len erg (g cm²/s²); the integrand is dimensionless.
#include "knit/energy/segment_accumulator.hpp"
#include "knit/energy/term.hpp"

namespace knit {

/// Length energy of one segment; adds ∂E/∂x into *grad.
double length_kernel(const Vector12d& x, double rest_length, double k_len,
                     const QuadratureTable& quad, Vector12d* grad);

/// length_kernel for lanes::LANES segments at once (see bending_kernel_lanes).
lanes::VecD length_kernel_lanes(const lanes::VecD x[12], lanes::VecD rest_length, double k_len,
                                const QuadratureTable& quad, lanes::VecD grad[12]);

class LengthEnergy final : public Term {
 public:
  std::string_view name() const override { return "length"; }
  double add_force(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                   double time, Eigen::VectorXd& force) override;

 private:
  SegmentAccumulator m_acc;
};

}  // namespace knit
