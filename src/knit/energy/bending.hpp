#pragma once
// Bending energy (MODEL.md §3, paper §4.1 eq. 4), quadratic in unsigned curvature:
//   E_i = k_bend ℓ_i ∫₀¹ κ_i(t)² dt,   κ² = |y'×y''|² / |y'|⁶
// κ² is used directly (no square root), so the energy is smooth for a straight yarn.
// |y'|² is regularised by a tiny ε (BEND_EPS) so coincident control points stay finite.
// Units: k_bend g cm³/s², ℓ cm, κ 1/cm (in arclength) → erg.
#include "knit/energy/segment_accumulator.hpp"
#include "knit/energy/term.hpp"

namespace knit {

/// The bending energy of one segment (T = double) or of lanes::LANES segments side by side
/// (T = lanes::VecD, one segment per lane): x[c] is coordinate c of the segment's 12
/// control-point coordinates; with `grad`, overwrites it with ∂E/∂x. Returns the energy.
/// One formula for the scalar and the vector path (instantiated for both in bending.cpp).
template <class T>
T bending_kernel_t(const T x[12], T rest_length, double k_bend, const QuadratureTable& quad,
                   T* grad);

/// bending_kernel_t on one segment as an Eigen vector; adds ∂E/∂x into *grad.
double bending_kernel(const Vector12d& x, double rest_length, double k_bend,
                      const QuadratureTable& quad, Vector12d* grad);

/// bending_kernel_t for lanes::LANES segments at once.
lanes::VecD bending_kernel_lanes(const lanes::VecD x[12], lanes::VecD rest_length, double k_bend,
                                 const QuadratureTable& quad, lanes::VecD grad[12]);

class BendingEnergy final : public Term {
 public:
  std::string_view name() const override { return "bending"; }
  double add_force(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                   double time, Eigen::VectorXd& force) override;

 private:
  SegmentAccumulator m_acc;
};

}  // namespace knit
