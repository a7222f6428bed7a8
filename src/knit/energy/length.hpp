#pragma once
// Length energy (MODEL.md §3, paper eq. 6): keeps the parameterisation speed uniform so
// mass does not slide along the curve.
//   E_i = k_len ∫₀¹ (1 − |y_i'(t)| / ℓ_i)² dt
// Units: k_len erg (g cm²/s²); the integrand is dimensionless.
#include "knit/energy/segment_accumulator.hpp"
#include "knit/energy/term.hpp"

namespace knit {

/// The length energy of one segment (T = double) or of lanes::LANES segments side by side
/// (T = lanes::VecD), as bending_kernel_t: one formula for both paths.
template <class T>
T length_kernel_t(const T x[12], T rest_length, double k_len, const QuadratureTable& quad, T* grad);

/// length_kernel_t on one segment as an Eigen vector; adds ∂E/∂x into *grad.
double length_kernel(const Vector12d& x, double rest_length, double k_len,
                     const QuadratureTable& quad, Vector12d* grad);

/// length_kernel_t for lanes::LANES segments at once.
lanes::VecD length_kernel_lanes(const lanes::VecD x[12], lanes::VecD rest_length, double k_len,
                                const QuadratureTable& quad, lanes::VecD grad[12]);

/// Which Hessian length_hessian gives. With g = 1 − |y'|/ℓ and u = y'/|y'|, per control
/// points a, b:
///   EXACT      2 k ∫ B_a' B_b' [ u uᵀ / ℓ² − g (I − u uᵀ) / (ℓ |y'|) ] dt
///   PROJECTED  the same with g replaced by min(g, 0): the stiffness along the yarn and
///              the tension's transverse stiffness where the yarn is stretched, without
///              the negative transverse part where it is compressed. Positive
///              semidefinite; equal to EXACT wherever no quadrature point is compressed.
enum class LengthHessian { EXACT, PROJECTED };

/// The Hessian ∂²E/∂x² of one segment's length energy (12×12, erg/cm² = g/s²), with the
/// quadrature of length_kernel.
Matrix12d length_hessian(const Vector12d& x, double rest_length, double k_len,
                         const QuadratureTable& quad, LengthHessian kind);

class LengthEnergy final : public Term {
 public:
  std::string_view name() const override { return "length"; }
  double add_force(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                   double time, Eigen::VectorXd& force) override;
  /// The PROJECTED stiffness of every segment (length_hessian): the linearly implicit
  /// integrator takes this term implicitly.
  bool has_stiffness() const override { return true; }
  bool reads_velocity() const override { return false; }
  void segment_stiffness(const Model& model, const Eigen::VectorXd& q,
                         std::vector<Matrix12d>& blocks) override;

 private:
  SegmentAccumulator m_acc;
};

}  // namespace knit
