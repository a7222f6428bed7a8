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

/// Which Hessian bending_hessian gives.
///   EXACT      ∂²E/∂x² of the quadrature above: per point, with a = y', b = y'',
///              C = |a×b|², g = s⁻³ (s = |a|² + ε), κ² = C g,
///                ∂²κ²/∂a² = g C_aa + C_a g_aᵀ + g_a C_aᵀ + C g_aa,
///                ∂²κ²/∂a∂b = g C_ab + g_a C_bᵀ,   ∂²κ²/∂b² = g C_bb,
///              C_aa = 2|b|² I − 2bbᵀ, C_bb = 2|a|² I − 2aaᵀ, C_ab = 4abᵀ − 2baᵀ − 2(a·b) I,
///              g_a = −6 s⁻⁴ a, g_aa = −6 s⁻⁴ I + 48 s⁻⁵ aaᵀ; mapped to the control points
///              by y' = Σ B_i' x_i, y'' = Σ B_i'' x_i. Indefinite where the yarn bends.
///   PROJECTED  the nearest positive semidefinite matrix (its negative eigenvalues set to
///              zero), for the implicit step: equal to EXACT where that is semidefinite.
/// The Gauss–Newton part alone (2 k ℓ Σ w JᵀJ with J = ∂(y'×y''/s^{3/2})/∂x) was tried and
/// is too soft where the knit's loops bend tightly: on the 42×32 it held 2e-3 s, not 3.2e-3.
enum class BendingHessian { EXACT, PROJECTED };

/// The Hessian of one segment's bending energy (12×12, g/s²), with the quadrature of
/// bending_kernel.
Matrix12d bending_hessian(const Vector12d& x, double rest_length, double k_bend,
                          const QuadratureTable& quad, BendingHessian kind);

class BendingEnergy final : public Term {
 public:
  /// `implicit`: the IMEX integrators take this term implicitly (SolverSettings::
  /// implicit_bending), with bending_hessian's PROJECTED Hessian as its stiffness.
  explicit BendingEnergy(bool implicit = false) : m_implicit(implicit) {}
  std::string_view name() const override { return "bending"; }
  double add_force(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                   double time, Eigen::VectorXd& force) override;
  bool has_stiffness() const override { return m_implicit; }
  bool reads_velocity() const override { return false; }
  void segment_stiffness(const Model& model, const Eigen::VectorXd& q,
                         std::vector<Matrix12d>& blocks) override;

 private:
  SegmentAccumulator m_acc;
  bool m_implicit;
};

}  // namespace knit
