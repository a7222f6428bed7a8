#pragma once
// Parameters in three groups (MODEL.md §8, Table 1), CGS units throughout. Each default
// lives here and nowhere else; the presets are the table's two columns.
//   Material        what the yarn is: radius, mass per length, stiffnesses, damping
//   Discretisation  how the yarn is sampled: quadrature and contact points per segment
//   SolverSettings  how time is stepped: time step, constraints, tolerances
// Gravity belongs to the scene the yarn is in and sits beside the three groups.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace knit {

/// The yarn's physical properties (MODEL.md §8).
struct Material {
  double radius = 0.125;       ///< yarn radius r (cm)
  double density = 0.006;      ///< mass per unit length μ (g/cm)
  double k_len = 2000;         ///< length energy stiffness (g cm²/s²)
  double k_bend = 5;           ///< bending stiffness (g cm³/s²)
  double k_global = 0;         ///< global (mass-proportional) damping (g/s)
  double k_contact = 3250;     ///< yarn–yarn contact stiffness (erg/cm² = g/s²)
  double k_dt = 0.003;         ///< tangential contact damping (g/(cm² s))
  double k_dn = 0.03;          ///< normal contact damping (g/(cm² s))
  double alpha_small = 0.675;  ///< non-rigid damping, small regions ∈ [0,1] per step of
                               ///< 1/11800 s (a rate: per_step_strength)
  double alpha_large = 0.3;    ///< non-rigid damping, large regions, the same
  bool contact = true;         ///< yarn–yarn contact on/off
  /// yarn–yarn Coulomb friction coefficient μ (filters/yarn_friction.hpp; not in the
  /// paper's model, whose only friction is the viscous contact damping): 0 = off
  double yarn_friction = 0;
};

/// Sampling of each spline segment.
struct Discretisation {
  int quadrature_points = 11;  ///< Simpson points per segment for the energies (odd)
  int contact_points = 10;     ///< contact quadrature points per segment (MODEL.md §8: 10–20)
  /// The two control points at each end of a yarn get at least this fraction of the mean
  /// lumped mass of its interior control points. 0 (the default) keeps MODEL.md's row sums,
  /// which give a yarn's last control point 1/24 of an interior one's and the one before
  /// it 1/2: an artefact of the lumping that bounds the explicit step where an end is free
  /// and undamped (docs/model.md §2). 0.5 adds about half a segment's mass at each end.
  double end_mass_floor = 0;
};

/// How a step integrates the forces before the projection and the filters:
///   EXPLICIT  explicit midpoint for every term (MODEL.md §5.2; the reference)
///   IMEX      explicit midpoint for every term but those that give a stiffness (the
///             length energy), which take one linearly implicit Euler step instead
///             (docs/model.md §5.2). Their stiffness along the yarn bounds the explicit
///             step (bench_step_limit); taken implicitly it no longer does.
///   IMEX_CONTACT  IMEX with yarn–yarn contact implicit too: its force at the step's start
///             and its normal stiffness (the projected Hessian, contact_kernel.hpp) in the
///             linear solve, which conjugate gradients solve with the length energy's band
///             factor as the preconditioner. In simulation, contact is what bounds IMEX's step.
enum class Integrator { EXPLICIT, IMEX, IMEX_CONTACT };
/// "explicit", "imex" or "imex-contact".
const char* integrator_name(Integrator integrator);
/// Whether the integrator takes the stiff terms by a linearly implicit step (IMEX or
/// IMEX_CONTACT).
inline bool is_imex(Integrator integrator) {
  return integrator != Integrator::EXPLICIT;
}
/// Every integrator's name, in enum order.
const std::vector<std::string>& integrator_names();
/// The integrator named `name`; throws std::invalid_argument naming the known ones.
Integrator parse_integrator(const std::string& name);

/// Time stepping and constraint projection.
struct SolverSettings {
  double time_step = 1.0 / 11800;  ///< h (s), MODEL.md §8
  Integrator integrator = Integrator::EXPLICIT;
  /// With IMEX or IMEX_CONTACT, the bending energy implicit too (its Hessian made
  /// positive semidefinite, bending_hessian, in the band solve): explicit bending bounds
  /// imex-contact's step (1.6e-3 s with k_bend = 5 on a 42×32 knit; 3.2e-3 s with it).
  bool implicit_bending = false;
  /// With IMEX_CONTACT: 0 (the default) solves each step once with the band factor, which
  /// holds the contact stiffness on each segment's own control points, and takes the
  /// contact coupling between segments at the step's start velocity (−h² K_c v on the
  /// right-hand side); > 0 solves the whole linear system by conjugate gradients until the
  /// residual is this fraction of the right-hand side (docs/model.md §5.2).
  double contact_solve_tolerance = 0;
  /// With IMEX_CONTACT: > 0 reuses an exact contact evaluation's linearisation while every
  /// control point stays within this many yarn radii of where it was evaluated
  /// (ContactTerm::add_force); 0 (the default) evaluates contact afresh every step.
  double contact_reuse = 0;
  bool length_constraints = true;      ///< enforce C_i = 0 by projection (off in relaxation)
  double constraint_tolerance = 1e-6;  ///< projection stops when max |C| is below (C_len is
                                       ///< dimensionless, pin/glue/clamp rows in cm)
  int max_projection_iterations = 20;
  /// A step that fails (unstable, non-finite, projection not converged) is taken again
  /// from where it started in two halves, and so on, up to this many halvings (h / 2ⁿ);
  /// the halved step is kept for a while before the step tries h again (the runner,
  /// runner.hpp). 0 (the default) stops the run at the first failed step.
  int max_step_halvings = 0;
};

struct Params {
  Material material;
  Discretisation discretisation;
  SolverSettings solver;
  Eigen::Vector3d gravity{0, 0, -981};  ///< cm/s²

  /// MODEL.md §8, simulation column.
  static Params simulation() { return Params{}; }
  /// MODEL.md §8, relaxation column (length constraints off, stiff length energy, strong
  /// global damping, soft bending).
  static Params relaxation() {
    Params p;
    p.material.k_len = 10000;
    p.material.k_bend = 0.005;
    p.material.k_global = 1.5;
    p.material.alpha_small = 0.3;
    p.material.alpha_large = 0.3;
    p.solver.length_constraints = false;
    return p;
  }
};

/// The working range of a numeric parameter: every value knitsim accepts is finite and
/// inside it (inclusive). Scene files, the command line and the Python module check
/// against these ranges before anything runs.
struct ParamRange {
  const char* name;  ///< the key in a scene's "params" (and, with '-', the option name)
  double min, max;
  const char* unit;
};

/// Every numeric parameter's range, in the order of the structs above.
const std::vector<ParamRange>& param_ranges();
/// The range of parameter `name`; throws std::out_of_range for an unknown name.
const ParamRange& param_range(const std::string& name);

/// Throws std::invalid_argument naming `name`, its value and its range when `value` is not
/// finite or outside param_range(name).
void check_param(const std::string& name, double value);

/// Checks every field of `p` (see param_ranges(); quadrature_points must also be odd,
/// gravity finite and at most 1e5 cm/s² per axis); throws std::invalid_argument naming the
/// first bad field.
void validate_params(const Params& p);

/// Longest simulated duration one run may be asked for (s).
inline constexpr double MAX_DURATION = 1e5;

/// Throws std::invalid_argument unless `duration` (s) is finite, in (0, MAX_DURATION] and
/// at least one `time_step` long.
void check_duration(double duration, double time_step);

/// A number for messages: at most 6 significant digits ("1e+308", not 309 digits).
std::string short_number(double x);
/// The time left of a run at `from` that ends at `to` with steps of `step`, written for a
/// command that goes on with it (its --max-time): short ("0.005", not
/// "0.0050000000000004138") where that changes nothing the run does, else exact. Exact:
/// the shortest decimal d for which from + d == to in double arithmetic. Short: when the
/// time left is a whole number n of steps (to 1e-9 of a step), the shortest decimal that
/// is n steps to 1e-9 of a step: the run goes on with the same n steps of `step`
/// (runner.cpp's ends are judged to a millionth of a step).
std::string time_left_text(double from, double to, double step);

}  // namespace knit
