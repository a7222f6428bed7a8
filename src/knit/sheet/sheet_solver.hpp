#pragma once
// Time stepping and statics of the elastic sheet (Baraff & Witkin 1998 §5).
//
// Implicit Euler, linearised once per step (BW eq. 16–17): with M the lumped masses (g),
// K = ∂f/∂x (PSD-Hessian version, dyn/cm) and D = ∂f/∂v (dyn·s/cm) at (x₀, v₀),
//   (M − h D − h² K) Δv = h (f₀ + h K v₀),   v₁ = v₀ + Δv,   x₁ = x₀ + h v₁.
// The matrix is symmetric positive definite (−K and −D are PSD), and is solved by
// Eigen's conjugate gradient with a diagonal (Jacobi) preconditioner.
//
// Constraints: sets of nodes moved rigidly at a prescribed velocity V (cm/s; zero holds
// them). Their degrees of freedom are eliminated: Δv of a constrained node is V − v₀, the
// free rows are solved with those columns moved to the right-hand side, and the node moves
// by x₁ = x₀ + h V exactly.
//
// Reaction force (sign convention): the force the clamp applies TO THE SHEET, summed over
// the set's nodes, dyn. Per node it is what makes the node follow its prescribed motion:
//   dynamics:  R = m Δv/h − (f₀ + K h v₁ + D Δv)   (mass × acceleration − the linearised
//              internal + external force of the step)
//   statics:   R = −f(x)                           (it balances the node's force)
// So a clamp holding a hanging sheet reports +weight upward, and a clamp pulling a strip
// along +u reports a force along +u.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "knit/sheet/bw_energy.hpp"
#include "knit/sheet/sheet.hpp"

namespace knit::sheet {

/// Mutable state of a sheet.
struct SheetState {
  Eigen::VectorXd positions;   ///< cm, 3 per node
  Eigen::VectorXd velocities;  ///< cm/s, 3 per node
  double time = 0;             ///< s
};

/// The sheet at rest in its rest shape, time 0.
SheetState rest_state(const SheetMesh& mesh);

/// A set of nodes moved rigidly by a prescribed velocity (a clamp, a pin, a pulled edge).
struct SheetConstraint {
  std::string name;                                    ///< for reports
  std::vector<int> nodes;                              ///< node indices
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< cm/s
};

/// Settings of step_implicit_euler.
struct StepSettings {
  double h = 1e-3;                                        ///< time step, s (> 0)
  Eigen::Vector3d gravity = Eigen::Vector3d(0, 0, -981);  ///< cm/s²
  double cg_tolerance = 1e-10;  ///< CG's relative residual ‖r‖/‖b‖
  int cg_max_iterations = 10000;
};

/// What one step did.
struct StepReport {
  int cg_iterations = 0;                   ///< conjugate-gradient iterations
  double cg_error = 0;                     ///< CG's final relative residual
  std::vector<Eigen::Vector3d> reactions;  ///< per constraint, dyn, clamp on sheet
  double potential_energy = 0;             ///< at the start of the step, erg
  double kinetic_energy = 0;               ///< ½ Σ m v² after the step, erg
};

/// Advances `state` by one linearised implicit Euler step (header comment). Throws
/// std::invalid_argument for a bad step size, state sizes or constraints (node out of
/// range or in two sets), and std::runtime_error when CG fails or the step produces
/// non-finite values; `state` is then left unchanged.
StepReport step_implicit_euler(const SheetMesh& mesh, const SheetMaterial& material,
                               const std::vector<SheetConstraint>& constraints,
                               const StepSettings& settings, SheetState& state);

/// Moves every constraint's nodes by velocity·dt (cm), for quasi-static loading: move the
/// clamps, then solve_static.
void move_constraints(const std::vector<SheetConstraint>& constraints, double dt,
                      SheetState& state);

/// Settings of solve_static.
struct StaticSettings {
  Eigen::Vector3d gravity = Eigen::Vector3d(0, 0, -981);  ///< cm/s²
  int max_iterations = 100;                               ///< Newton iterations
  double force_tolerance = 1e-9;      ///< converged when max |f| on a free DOF ≤ this, dyn …
  double relative_tolerance = 1e-10;  ///< … or ≤ this × its value at the start
  /// The Newton matrix. PROJECTED (the default): the exact Hessian where it is positive
  /// definite, shifted on its diagonal (up to 1e-3 of it) or each element's projected onto
  /// the PSD matrices where not, with the saddle check below: it reaches a bias pull's
  /// wrinkled minimum, which PSD (BW's Gauss–Newton shear and bend, no check) stops short of
  /// or creeps toward. PSD: Gauss–Newton, cheaper per iteration, for sheets that stay
  /// near flat (docs/core.md). Not NONE or EXACT.
  Jacobians hessian = Jacobians::PROJECTED;
  /// PROJECTED: how many times a solve may leave a saddle it converged to (below)
  int max_escapes = 20;
};

/// What solve_static did.
struct StaticReport {
  bool converged = false;
  /// PROJECTED: the equilibrium is a minimum (the exact Hessian on the free nodes positive
  /// definite); false for PSD, and where max_escapes saddles were left and it still is one
  bool stable = false;
  int escapes = 0;                         ///< saddles left along negative curvature
  int iterations = 0;                      ///< Newton iterations
  int factorizations = 0;                  ///< sparse LDLᵀ factorisations (the solve's cost)
  int projected_iterations = 0;            ///< PROJECTED: iterations on the projected matrix
  double residual = 0;                     ///< max |f| over free DOFs at the end, dyn
  double energy = 0;                       ///< potential energy at the end, erg
  std::vector<Eigen::Vector3d> reactions;  ///< per constraint, dyn, clamp on sheet (−Σ f)
};

/// Finds the equilibrium of the free nodes with the constrained nodes held where `state`
/// has them: Newton iterations on settings.hessian (bw_energy.hpp) with a sparse Cholesky
/// solve (a multiple of the identity is added where it is not positive definite) and a backtracking
/// line search on the potential energy. With PROJECTED an equilibrium it converges to is
/// checked by the exact Hessian: a saddle (a flat sheet compressed across a pull, which a
/// thin sheet leaves by wrinkling) is left along its direction of negative curvature and
/// the iterations go on, so that the solve ends at a stable equilibrium (report.stable).
/// Sets all velocities to zero; time is unchanged.
/// Does not throw when it does not converge: check StaticReport::converged.
StaticReport solve_static(const SheetMesh& mesh, const SheetMaterial& material,
                          const std::vector<SheetConstraint>& constraints,
                          const StaticSettings& settings, SheetState& state);

}  // namespace knit::sheet
