#pragma once
// Yarn–yarn contact between two spline segments (MODEL.md §3 "Yarn–yarn contact" and §4
// "Contact damping"; Kaldor, James & Marschner 2008, §4.2 and §4.3). These are the plain,
// dense reference kernels on fixed-size Eigen types: every point pair of the contact
// quadrature is evaluated. ContactTerm (contact_term.hpp) uses an optimised copy of the
// same formulas on culled point pairs and is tested against these.
//
// Notation. Segment i has control points x_i (Vector12d, cm) and rest length ℓ_i (cm);
// y_i(t) = Σ_a B_a(t) x_{i,a}. The contact quadrature (Model::contact_quad, midpoint rule
// with Params::contact_points abscissae t_a and weights w_a) discretises both integrals.
// With r the yarn radius (cm) and d_ab = |y_j(t_b) − y_i(t_a)| / 2r (dimensionless):
//
//   E_ij = k_contact ℓ_i ℓ_j Σ_a Σ_b w_a w_b f(d_ab),   f(d) = 1/d² + d² − 2 (d < 1), else 0
//
// k_contact is an energy per unit length² (erg/cm² = g/s²), so E_ij is in erg. f and f'
// vanish at d = 1 (the tubes just touch), f → ∞ as d → 0.
//
//   D_ij = ℓ_i ℓ_j Σ_a Σ_b w_a w_b [k_dt |Δv|² − (k_dt − k_dn)(n̂·Δv)²]   over d_ab < 1 only
//   Δv = v_j(t_b) − v_i(t_a),   n̂ = (y_j(t_b) − y_i(t_a)) / |y_j(t_b) − y_i(t_a)|
//
// k_dt, k_dn in g/(cm² s), velocities in cm/s, so D_ij is in erg/s. Convention (MODEL.md
// §2): D is used as written, without a factor ½, and the damping force is −∂D/∂q̇,
// i.e. per point pair  F_j = −2 ℓ_i ℓ_j w_a w_b [k_dt Δv − (k_dt − k_dn)(n̂·Δv) n̂]  on
// y_j(t_b) and F_i = −F_j on y_i(t_a) (dyn), spread to control points with the basis.
// D is a non-negative quadratic form (= k_dt|Δv_⊥|² + k_dn(n̂·Δv)² per pair), so the
// damping power q̇ᵀF = −2D ≤ 0: it only removes energy. It damps relative motion only,
// so it conserves linear momentum; its tangential part does exert a couple (it stands in
// for friction), so it does not conserve angular momentum, while the contact energy does.
#include <Eigen/Core>
#include <limits>

#include "knit/model/params.hpp"
#include "knit/spline/basis.hpp"

namespace knit {

/// f(d) = 1/d² + d² − 2 for d < 1, 0 otherwise (dimensionless). Infinite at d = 0.
inline double contact_potential(double d) {
  if (!(d < 1.0)) return 0.0;
  const double d2 = d * d;
  return 1.0 / d2 + d2 - 2.0;
}

/// f'(d) = −2/d³ + 2d for d < 1, 0 otherwise.
inline double contact_potential_d1(double d) {
  if (!(d < 1.0)) return 0.0;
  return -2.0 / (d * d * d) + 2.0 * d;
}

/// f''(d) = 6/d⁴ + 2 for d < 1, 0 otherwise (f'' jumps at d = 1, where f and f' vanish).
inline double contact_potential_d2(double d) {
  if (!(d < 1.0)) return 0.0;
  const double d2 = d * d;
  return 6.0 / (d2 * d2) + 2.0;
}

/// Which Hessian contact_pair_hessian gives. Per point pair in contact, with Δ = y_j(t_b) −
/// y_i(t_a), n̂ = Δ/|Δ| and c = k ℓ_i ℓ_j w_a w_b, the Hessian of c f(|Δ|/2r) in Δ is
///   c f''(d)/(2r)² n̂n̂ᵀ + c f'(d)/(2r |Δ|) (I − n̂n̂ᵀ).
/// f' < 0 inside the contact distance, so the transverse part is negative: EXACT keeps it,
/// PROJECTED (positive semidefinite) drops it — the stiffness of the normal direction
/// alone, what resists the tubes' approach — and MIRRORED (positive semidefinite, what the
/// IMEX_CONTACT step uses) takes its absolute value, c |f'(d)|/(2r |Δ|) (I − n̂n̂ᵀ): the
/// rate at which the force turns as the pair slides past each other, which a step taken
/// with the normals held fixed otherwise leaves out. MIRRORED = 2 PROJECTED − EXACT.
enum class ContactHessian { EXACT, PROJECTED, MIRRORED };

/// Result of one segment pair: energy, forces and a count of the point pairs in contact.
struct ContactPairResult {
  double energy = 0;                      ///< E_ij (erg)
  Vector12d force_i = Vector12d::Zero();  ///< −∂E/∂x_i − ∂D/∂ẋ_i (dyn)
  Vector12d force_j = Vector12d::Zero();  ///< −∂E/∂x_j − ∂D/∂ẋ_j (dyn)
  int point_pairs_in_contact = 0;         ///< point pairs with d < 1
  double min_distance_ratio = std::numeric_limits<double>::infinity();  ///< min d over all pairs
};

/// Contact energy E_ij (erg) of segments i, j (dense over all point pairs).
double contact_pair_energy(const Vector12d& xi, const Vector12d& xj, double li, double lj,
                           const Params& params, const QuadratureTable& quad);

/// E_ij (erg); overwrites grad_i = ∂E/∂x_i and grad_j = ∂E/∂x_j (dyn).
double contact_pair_gradient(const Vector12d& xi, const Vector12d& xj, double li, double lj,
                             const Params& params, const QuadratureTable& quad, Vector12d& grad_i,
                             Vector12d& grad_j);

/// The 24×24 Hessian of E_ij in (x_i, x_j) (g/s² = dyn/cm), dense over all point pairs; a
/// point pair's block is J_pᵀ H_p J_p with J_p the map from the 24 coordinates to Δ
/// (−B_a(t_a) on x_i, B_b(t_b) on x_j) and H_p as ContactHessian says.
Eigen::Matrix<double, 24, 24> contact_pair_hessian(const Vector12d& xi, const Vector12d& xj,
                                                   double li, double lj, const Params& params,
                                                   const QuadratureTable& quad,
                                                   ContactHessian kind);

/// Contact damping D_ij (erg/s) for control-point velocities vi, vj (cm/s).
double contact_pair_damping(const Vector12d& xi, const Vector12d& xj, const Vector12d& vi,
                            const Vector12d& vj, double li, double lj, const Params& params,
                            const QuadratureTable& quad);

/// Overwrites force_i = −∂D_ij/∂ẋ_i and force_j = −∂D_ij/∂ẋ_j (dyn).
void contact_pair_damping_force(const Vector12d& xi, const Vector12d& xj, const Vector12d& vi,
                                const Vector12d& vj, double li, double lj, const Params& params,
                                const QuadratureTable& quad, Vector12d& force_i,
                                Vector12d& force_j);

/// Everything at once: energy, contact + damping forces, contact count, min d.
ContactPairResult contact_pair_force(const Vector12d& xi, const Vector12d& xj, const Vector12d& vi,
                                     const Vector12d& vj, double li, double lj,
                                     const Params& params, const QuadratureTable& quad);

}  // namespace knit
