#pragma once
// Global (mass-proportional) damping (MODEL.md §4, paper eq. 9):
//   D_i = k_global ∫₀¹ v_i(t)ᵀ v_i(t) dt
// lumped by row sums exactly as the mass matrix is (MODEL.md §2):
//   D_i ≈ k_global Σ_a (∫₀¹ B_a) |q̇_{i+a}|²,   force_k = −∂D/∂q̇_k = −2 k_global w_k q̇_k
// with w_k = Σ_i ∫B_{k−i} = M_k / (μ ℓ). The consistent form damps the end control points of
// a yarn ~20× more weakly than their lumped mass would need (B_0² vs B_0), leaving slow
// ringing at pinned ends; the lumped form damps every control point at the same rate
// 2 k_global / (μ ℓ), which is what mass-proportional damping means.
// D is used as written (no factor ½), so the force carries the factor 2.
// Units: k_global g/s → force in dyn.
#include "knit/energy/segment_accumulator.hpp"
#include "knit/energy/term.hpp"

namespace knit {

/// Lumped damping "energy" D of one segment with control-point velocities `u`; adds ∂D/∂u.
double global_damping_kernel(const Vector12d& u, double k_global, Vector12d* grad);

class GlobalDamping final : public Term {
 public:
  std::string_view name() const override { return "global_damping"; }
  double add_force(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                   double time, Eigen::VectorXd& force) override;
  double energy(const Model&, const Eigen::VectorXd&, double) override { return 0; }

 private:
  SegmentAccumulator m_acc;
};

}  // namespace knit
