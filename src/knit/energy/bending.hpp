#pragma once
// Bending energy (MODEL.md §3, paper §4.1 eq. 4), quadratic in unsigned curvature:
//   E_i = k_bend ℓ_i ∫₀¹ κ_i(t)² dt,   κ² = |y'×y''|² / |y'|⁶
// κ² is used directly (no square root), so the energy is smooth for a straight yarn.
// |y'|² is regularised by a tiny ε (BEND_EPS) so coincident control points stay finite.
// Units: k_bend g cm³/s², ℓ cm, κ 1/cm (in arclength) → erg.
#include "knit/energy/segment_accumulator.hpp"
#include "knit/energy/term.hpp"

namespace knit {

/// Bending energy of one segment with control points `x`; adds ∂E/∂x into *grad.
double bending_kernel(const Vector12d& x, double rest_length, double k_bend,
                      const QuadratureTable& quad, Vector12d* grad);

/// bending_kernel for lanes::LANES segments at once, one per lane: x[c] is coordinate c of
/// the 12 control-point coordinates of every lane's segment; overwrites grad with ∂E/∂x
/// and returns every lane's energy. The same operations as bending_kernel, lane by lane.
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
