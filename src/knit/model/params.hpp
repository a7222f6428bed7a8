#pragma once
// Parameters in three groups (MODEL.md §8, Table 1), CGS units throughout. Each default
// lives here and nowhere else; the presets are the table's two columns.
//   Material        what the yarn is: radius, mass per length, stiffnesses, damping
//   Discretisation  how the yarn is sampled: quadrature and contact points per segment
//   SolverSettings  how time is stepped: time step, constraints, tolerances
// Gravity belongs to the scene the yarn is in and sits beside the three groups.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace knit {

/// The yarn's physical properties (MODEL.md §8): its fields, defaults, units and ranges
/// are the KNIT_MATERIAL lines of params.def.
struct Material {
#define KNIT_MATERIAL(type, name, def, min, max, unit, doc) type name = def;
#include "knit/model/params.def"
};

/// Sampling of each spline segment: the KNIT_DISCRETISATION lines of params.def.
struct Discretisation {
#define KNIT_DISCRETISATION(type, name, def, min, max, unit, doc) type name = def;
#include "knit/model/params.def"
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

/// Time stepping and constraint projection: the KNIT_SOLVER lines of params.def.
struct SolverSettings {
#define KNIT_SOLVER(type, name, def, min, max, unit, doc) type name = def;
#include "knit/model/params.def"
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

/// What a parameter holds.
enum class ParamType { REAL, INTEGER, BOOLEAN, CHOICE };

/// One parameter as params.def declares it. Values pass through as doubles (an integer
/// as itself, a boolean as 0 or 1, a choice as its index in `choices`).
struct ParamDecl {
  const char* name;   ///< the field, the key in a scene's "params" and the summary's
  const char* group;  ///< "material", "discretisation" or "solver"
  ParamType type;
  double min, max;   ///< the working range, inclusive (numbers only)
  const char* unit;  ///< "" when dimensionless
  const char* doc;   ///< one line
  double (*get)(const Params&);
  void (*set)(Params&, double);
  /// the names a choice takes, in index order (empty for other types)
  const std::vector<std::string>& choices() const;
  /// The value `p` holds, as a scene or summary writes it (a number, true/false, a name).
  std::string text(const Params& p) const;
  /// The default (Params{}'s value) as text.
  std::string default_text() const;
  /// The option that sets it on the command line: "--" and the name with '-' for '_'.
  std::string option() const;
};

/// The value of `d` in `p` as JSON: a number (an integer as one), true/false, or a choice's
/// name, as scenes, summaries and state files write it.
nlohmann::json param_json(const ParamDecl& d, const Params& p);

/// Every parameter, in params.def's order.
const std::vector<ParamDecl>& param_table();
/// The parameter `name`; throws std::out_of_range for an unknown name.
const ParamDecl& param_decl(const std::string& name);

/// The working range of a numeric parameter (a view of its declaration, for front ends
/// that check a value before it is set).
struct ParamRange {
  const char* name;
  double min, max;
  const char* unit;
};
/// The range of parameter `name`; throws std::out_of_range for an unknown name.
ParamRange param_range(const std::string& name);

/// Throws std::invalid_argument naming `name`, its value and its range when `value` is not
/// finite or outside param_range(name).
void check_param(const std::string& name, double value);

/// Checks every field of `p` (see param_table(); quadrature_points must also be odd,
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
