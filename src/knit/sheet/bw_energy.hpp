#pragma once
// The three Baraff–Witkin conditions (BW98 §4) with energy E = ½ k C², exact gradients and
// Hessians, condition damping, and their assembly over a SheetMesh with gravity.
//
// Stretch (BW §4.2), per triangle, one condition per material direction:
//   [w_u w_v] = [Δx1 Δx2] D⁻¹                       (dimensionless; D in sheet.hpp)
//   C_u = √a (‖w_u‖ − 1),  C_v = √a (‖w_v‖ − 1)       (cm; a = rest area, cm²)
// Shear (BW §4.3), per triangle:
//   C_s = √a (w_u · w_v)                              (cm)
// Bend (BW §4.4), per interior edge with vertices x1, x2 (opposite) and x3, x4 (edge):
//   n1 = (x1 − x3) × (x1 − x4),  n2 = (x2 − x4) × (x2 − x3),  e = x4 − x3
//   θ = atan2((n1 × n2) · e, ‖e‖ n1 · n2)
//   C_b = w (θ − θ₀),  w = ‖n1‖ ‖n2‖ / (‖n1⁰‖ ‖n2⁰‖)   (radians; θ − θ₀ wrapped to (−π, π])
// θ is the signed angle between the two triangles' normals: 0 when flat, positive when the
// sheet folds one way, negative the other. BW's condition is θ − θ₀; the weight w, the
// product of the two triangles' areas over their rest areas, is ours: it is 1 in the rest
// shape and 1 + O(strain) near it, so the bend is BW's wherever the triangles keep their
// areas, and it goes to zero as either triangle collapses. There θ has no meaning (a
// collapsed triangle has no normal), ∂θ/∂x grows as 1/‖n‖ and ∂²θ/∂x² as 1/‖n‖², while
// w ∇θ and w² ∇²θ stay bounded: the bending force and its Hessian have a bound at any
// configuration. A sheet sheared hard along the bias needs it: past strain √2 − 1 its
// triangles must stretch or collapse, and a soft-sheared sheet's equilibrium collapses
// them (docs/core.md).
//
// Normalisation. BW scale the stretch and shear conditions by a (C = a(‖w‖ − 1)); then
// E = ½ k a² ε² per triangle and a uniform strain ε stores ½ k ε² Σ a², which depends on the
// resolution (Σ a² = A²/n_triangles for equal triangles). We use √a instead, so that
//   E_stretch = ½ a (k_stretch_u (‖w_u‖ − 1)² + k_stretch_v (‖w_v‖ − 1)²),
//   E_shear = ½ k_shear a (w_u · w_v)²,
// the energy per rest area is ½ k ε², and k_stretch_u, k_stretch_v are the sheet's 2-D
// Young moduli along u and v (dyn/cm) whatever the mesh. (There is no Poisson coupling: w_u and w_v
// are penalised separately, so the Poisson ratio is 0 — a strip pulled along u keeps its width.)
// E_bend = ½ k_bend C_b² with k_bend in erg; for a sheet bent uniformly this sums to about
// ½ k_bend κ² A times a factor set by the triangulation, independent of the resolution.
//
// Derivatives. With w_u = Σᵢ αᵢ xᵢ, w_v = Σᵢ βᵢ xᵢ (α, β from D⁻¹, Σαᵢ = Σβᵢ = 0):
//   ∂C_u/∂xᵢ = √a αᵢ ŵ_u,           ∂²C_u/∂xᵢ∂xⱼ = √a αᵢ αⱼ (I − ŵ_u ŵ_uᵀ)/‖w_u‖
//   ∂C_s/∂xᵢ = √a (αᵢ w_v + βᵢ w_u), ∂²C_s/∂xᵢ∂xⱼ = √a (αᵢ βⱼ + βᵢ αⱼ) I
//   ∂θ/∂x1 = −‖e‖ n1/‖n1‖²,  ∂θ/∂x2 = −‖e‖ n2/‖n2‖²,
//   ∂θ/∂x3 = −((x1 − x4)·ê n1/‖n1‖² + (x2 − x4)·ê n2/‖n2‖²),
//   ∂θ/∂x4 =   (x1 − x3)·ê n1/‖n1‖² + (x2 − x3)·ê n2/‖n2‖²       (Bridson et al. 2003)
//   ∂C_b/∂x = w ∂θ/∂x + (θ − θ₀) ∂w/∂x, with ∂‖n‖/∂a = n̂ × (c − b) for n = (b − a) × (c − a)
// ∂²C_b/∂x² is computed exactly by second-order forward-mode differentiation (jet.hpp).
// Degenerate configurations (‖w‖ = 0; a collapsed bending triangle, where C_b = 0) get a
// zero gradient.
//
// Hessians of E = ½ k C²:
//   EXACT: k (∇C ∇Cᵀ + C ∇²C)                      — for finite-difference tests and Newton
//   PSD:   k (∇C ∇Cᵀ + max(C, 0) ∇²C) for stretch  — ∇²C_u is PSD, so this is the exact
//          Hessian under tension and BW's Gauss–Newton one under compression;
//          k ∇C ∇Cᵀ for shear and bend            — BW's choice: drop C ∇²C (indefinite).
//   PROJECTED: each element's exact Hessian (a triangle's stretch and shear together, a
//          hinge's bend) with its negative eigenvalues set to zero — the nearest PSD matrix
//          to it (projected Newton). It keeps the curvature that PSD drops wherever that
//          curvature is positive, which is what a shear-dominated (bias) statics needs to
//          converge in few Newton iterations; PSD's Gauss–Newton shear converges linearly.
// All are translation invariant (rows sum to zero), so an implicit step keeps momentum.
//
// Damping (BW §4.5): d = −k_d ∇C Ċ with Ċ = ∇Cᵀ v, velocity Jacobian ∂d/∂v = −k_d ∇C ∇Cᵀ;
// its position derivative is neglected, as in BW. Units: k_d in s·dyn/cm for stretch and
// shear, s·erg for bend; d in dyn.
//
// Gravity: E_g = −Σᵢ mᵢ g·xᵢ (erg), force mᵢ g (dyn), g in cm/s².
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <type_traits>

#include "knit/sheet/sheet.hpp"

namespace knit::sheet {

using Vector9d = Eigen::Matrix<double, 9, 1>;
using Matrix9d = Eigen::Matrix<double, 9, 9>;
using Vector12d = Eigen::Matrix<double, 12, 1>;
using Matrix12d = Eigen::Matrix<double, 12, 12>;

/// Which Hessian a kernel returns (see the header comment).
enum class HessianKind { EXACT, PSD };

/// A condition's value C and its derivatives with respect to the N stacked coordinates.
template <int N>
struct Condition {
  double c = 0;                      ///< C
  Eigen::Matrix<double, N, 1> grad;  ///< ∂C/∂x
  Eigen::Matrix<double, N, N> hess;  ///< ∂²C/∂x² (when requested)
  bool curvature_psd = false;        ///< ∂²C/∂x² is PSD (stretch)
  Condition()
      : grad(Eigen::Matrix<double, N, 1>::Zero()), hess(Eigen::Matrix<double, N, N>::Zero()) {}
};

/// The triangle's node positions stacked (x0, x1, x2), cm, from all positions x (3 per node).
Vector9d triangle_positions(const std::array<int, 3>& tri, const Eigen::VectorXd& x);
/// The hinge's node positions stacked (x1, x2, x3, x4) = (opposite[0], opposite[1],
/// edge[0], edge[1]), cm.
Vector12d hinge_positions(const SheetHinge& hinge, const Eigen::VectorXd& x);

/// Deformation gradient columns (w_u, w_v) of a triangle (dimensionless).
std::array<Eigen::Vector3d, 2> deformation_gradient(const Vector9d& x, const Eigen::Matrix2d& dinv);

/// Stretch conditions (C_u, C_v), cm, with gradients and, if `hessian`, second derivatives.
std::array<Condition<9>, 2> stretch_conditions(const Vector9d& x, const Eigen::Matrix2d& dinv,
                                               double area, bool hessian);
/// Shear condition C_s, cm.
Condition<9> shear_condition(const Vector9d& x, const Eigen::Matrix2d& dinv, double area,
                             bool hessian);
/// Signed dihedral angle θ of a hinge, radians in (−π, π]; 0 when flat.
double bend_angle(const Vector12d& x);
/// ‖n1‖ ‖n2‖ of a hinge (cm⁴): four times the product of its two triangles' areas.
double bend_area_product(const Vector12d& x);
/// Bend condition C_b = (‖n1‖ ‖n2‖ / rest_product)(θ − θ₀), θ − θ₀ wrapped to (−π, π]
/// (header comment); rest_product = bend_area_product in the rest shape (> 0, else
/// std::invalid_argument). Its Hessian is exact (jet.hpp).
Condition<12> bend_condition(const Vector12d& x, double rest_angle, double rest_product,
                             bool hessian);

/// E = ½ k C² (erg); adds ∂E/∂x = k C ∇C into *grad and the chosen Hessian into *hess
/// (either may be null; *hess needs a condition computed with its Hessian).
template <int N>
double condition_energy(const Condition<N>& c, double k,
                        std::type_identity_t<Eigen::Matrix<double, N, 1>>* grad,
                        std::type_identity_t<Eigen::Matrix<double, N, N>>* hess, HessianKind kind) {
  if (grad) *grad += k * c.c * c.grad;
  if (hess) {
    *hess += k * c.grad * c.grad.transpose();
    if (kind == HessianKind::EXACT)
      *hess += k * c.c * c.hess;
    else if (c.curvature_psd)
      *hess += k * std::max(c.c, 0.0) * c.hess;
  }
  return 0.5 * k * c.c * c.c;
}

/// Condition damping force d = −k_d ∇C (∇Cᵀ v) (dyn), added into *force, and its velocity
/// Jacobian −k_d ∇C ∇Cᵀ added into *dfdv (either may be null).
template <int N>
void condition_damping(const Condition<N>& c,
                       const std::type_identity_t<Eigen::Matrix<double, N, 1>>& v, double kd,
                       std::type_identity_t<Eigen::Matrix<double, N, 1>>* force,
                       std::type_identity_t<Eigen::Matrix<double, N, N>>* dfdv) {
  if (force) *force -= kd * c.grad.dot(v) * c.grad;
  if (dfdv) *dfdv -= kd * c.grad * c.grad.transpose();
}

/// Stretch energy ½ (k_u C_u² + k_v C_v²) of one triangle (erg); adds its gradient and
/// Hessian.
double stretch_energy(const Vector9d& x, const Eigen::Matrix2d& dinv, double area, double k_u,
                      double k_v, Vector9d* grad, Matrix9d* hess,
                      HessianKind kind = HessianKind::EXACT);
/// Shear energy ½ k C_s² of one triangle (erg); adds its gradient and Hessian.
double shear_energy(const Vector9d& x, const Eigen::Matrix2d& dinv, double area, double k,
                    Vector9d* grad, Matrix9d* hess, HessianKind kind = HessianKind::EXACT);
/// Bending energy ½ k C_b² of one hinge (erg); adds its gradient and Hessian.
double bend_energy(const Vector12d& x, double rest_angle, double rest_product, double k,
                   Vector12d* grad, Matrix12d* hess, HessianKind kind = HessianKind::EXACT);

/// Which Jacobians evaluate_forces assembles.
enum class Jacobians { NONE, PSD, EXACT, PROJECTED };

/// Energies, forces and Jacobians of the whole sheet at one state.
struct SheetForces {
  double elastic_energy = 0;  ///< stretch + shear + bend, erg
  double stretch_energy = 0;  ///< erg
  double shear_energy = 0;    ///< erg
  double bend_energy = 0;     ///< erg
  double gravity_energy = 0;  ///< −Σ mᵢ g·xᵢ, erg
  /// Potential energy elastic + gravity, erg (damping is not conservative).
  double energy() const { return elastic_energy + gravity_energy; }
  Eigen::VectorXd force;             ///< −∂E/∂x + damping, dyn, 3 per node
  Eigen::SparseMatrix<double> dfdx;  ///< ∂f/∂x = −(Hessian of E, PSD, EXACT or PROJECTED), dyn/cm
  Eigen::SparseMatrix<double> dfdv;  ///< ∂f/∂v of the damping forces, dyn·s/cm
};

/// Assembles energy, forces (elastic + damping + gravity) and, unless `jacobians` is NONE,
/// the stiffness Jacobian ∂f/∂x (damping's position derivative excluded) and the damping
/// Jacobian ∂f/∂v over the mesh. x, v: 3 per node (cm, cm/s); gravity in cm/s².
/// Throws std::invalid_argument when x or v has the wrong size.
SheetForces evaluate_forces(const SheetMesh& mesh, const SheetMaterial& material,
                            const Eigen::VectorXd& x, const Eigen::VectorXd& v,
                            const Eigen::Vector3d& gravity = Eigen::Vector3d(0, 0, -981),
                            Jacobians jacobians = Jacobians::PSD);

/// The same into `out`, reusing the storage of its matrices when they hold the mesh's
/// cached pattern from an earlier evaluation (an iterative solver's loop allocates nothing).
void evaluate_forces(const SheetMesh& mesh, const SheetMaterial& material, const Eigen::VectorXd& x,
                     const Eigen::VectorXd& v, const Eigen::Vector3d& gravity, Jacobians jacobians,
                     SheetForces& out);

/// Potential energy (elastic + gravity, erg) alone, for line searches.
double potential_energy(const SheetMesh& mesh, const SheetMaterial& material,
                        const Eigen::VectorXd& x,
                        const Eigen::Vector3d& gravity = Eigen::Vector3d(0, 0, -981));

}  // namespace knit::sheet
