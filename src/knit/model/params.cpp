#include "knit/model/params.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace knit {

const std::vector<ParamRange>& param_ranges() {
  // wide enough for any yarn a user may model, narrow enough that a typo (1e30, a
  // negative stiffness) is caught before it turns into a run that blows up
  static const std::vector<ParamRange> ranges = {
      {"radius", 1e-3, 10, "cm"},
      {"density", 1e-6, 100, "g/cm"},
      {"k_len", 0, 1e9, "g cm²/s²"},
      {"k_bend", 0, 1e6, "g cm³/s²"},
      {"k_global", 0, 1e6, "g/s"},
      {"k_contact", 0, 1e9, "g/s²"},
      {"k_dt", 0, 1e6, "g/(cm² s)"},
      {"k_dn", 0, 1e6, "g/(cm² s)"},
      {"alpha_small", 0, 1, ""},
      {"alpha_large", 0, 1, ""},
      {"yarn_friction", 0, 10, ""},
      {"quadrature_points", 3, 101, "points per segment"},
      {"contact_points", 1, 64, "points per segment"},
      {"end_mass_floor", 0, 1, "of an interior control point's mass"},
      {"time_step", 1e-8, 1e-2, "s"},
      {"contact_solve_tolerance", 0, 1, ""},
      {"contact_reuse", 0, 1, "yarn radii"},
      {"constraint_tolerance", 1e-12, 1, ""},
      {"max_projection_iterations", 1, 10000, ""},
      {"max_step_halvings", 0, 20, "halvings of the time step"},
  };
  return ranges;
}

const ParamRange& param_range(const std::string& name) {
  for (const ParamRange& r : param_ranges())
    if (name == r.name) return r;
  throw std::out_of_range("no parameter named " + name);
}

std::string short_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

std::string time_left_text(double from, double to, double step) {
  char buf[32];
  auto shortest = [&](auto&& good) {
    for (int digits = 1; digits <= 17; ++digits) {
      std::snprintf(buf, sizeof buf, "%.*g", digits, to - from);
      if (good(std::strtod(buf, nullptr))) return true;
    }
    return false;
  };
  const double steps = step > 0 ? (to - from) / step : 0;
  const double n = std::round(steps);
  constexpr double TOLERANCE = 1e-9;  // of a step
  if (n >= 1 && std::abs(steps - n) <= TOLERANCE &&
      shortest([&](double d) { return std::abs(d / step - n) <= TOLERANCE; }))
    return buf;
  if (shortest([&](double d) { return from + d == to; })) return buf;
  std::snprintf(buf, sizeof buf, "%.17g", to - from);
  return buf;
}

void check_param(const std::string& name, double value) {
  const ParamRange& r = param_range(name);
  if (std::isfinite(value) && value >= r.min && value <= r.max) return;
  std::string unit = r.unit[0] ? std::string(" ") + r.unit : std::string();
  throw std::invalid_argument(name + " = " + short_number(value) + " is " +
                              (std::isfinite(value) ? "outside" : "not a finite number in") +
                              " its working range [" + short_number(r.min) + ", " +
                              short_number(r.max) + "]" + unit);
}

void check_duration(double duration, double time_step) {
  if (!std::isfinite(duration) || duration <= 0 || duration > MAX_DURATION)
    throw std::invalid_argument("duration = " + short_number(duration) +
                                " s is outside its working range (0, " +
                                short_number(MAX_DURATION) + "] s");
  if (duration < time_step * (1 - 1e-6))
    throw std::invalid_argument("duration = " + short_number(duration) +
                                " s is shorter than one time step (" + short_number(time_step) +
                                " s)");
}

void validate_params(const Params& p) {
  const Material& m = p.material;
  check_param("radius", m.radius);
  check_param("density", m.density);
  check_param("k_len", m.k_len);
  check_param("k_bend", m.k_bend);
  check_param("k_global", m.k_global);
  check_param("k_contact", m.k_contact);
  check_param("k_dt", m.k_dt);
  check_param("k_dn", m.k_dn);
  check_param("alpha_small", m.alpha_small);
  check_param("alpha_large", m.alpha_large);
  check_param("yarn_friction", m.yarn_friction);
  check_param("quadrature_points", p.discretisation.quadrature_points);
  if (p.discretisation.quadrature_points % 2 == 0)
    throw std::invalid_argument(
        "quadrature_points = " + std::to_string(p.discretisation.quadrature_points) +
        " must be odd (Simpson's rule)");
  check_param("contact_points", p.discretisation.contact_points);
  check_param("end_mass_floor", p.discretisation.end_mass_floor);
  check_param("time_step", p.solver.time_step);
  check_param("contact_solve_tolerance", p.solver.contact_solve_tolerance);
  check_param("contact_reuse", p.solver.contact_reuse);
  if (p.solver.contact_reuse > 0 && p.solver.integrator != Integrator::IMEX_CONTACT)
    throw std::invalid_argument("contact_reuse = " + short_number(p.solver.contact_reuse) +
                                " needs the imex-contact integrator (its contact stiffness is "
                                "the linearisation reused)");
  check_param("constraint_tolerance", p.solver.constraint_tolerance);
  check_param("max_projection_iterations", p.solver.max_projection_iterations);
  check_param("max_step_halvings", p.solver.max_step_halvings);
  for (int c = 0; c < 3; ++c)
    if (!std::isfinite(p.gravity[c]) || std::abs(p.gravity[c]) > 1e5)
      throw std::invalid_argument("gravity[" + std::to_string(c) +
                                  "] = " + short_number(p.gravity[c]) +
                                  " is outside its working range [-1e5, 1e5] cm/s²");
}

const char* integrator_name(Integrator integrator) {
  switch (integrator) {
    case Integrator::IMEX:
      return "imex";
    case Integrator::IMEX_CONTACT:
      return "imex-contact";
    case Integrator::EXPLICIT:
      break;
  }
  return "explicit";
}

const std::vector<std::string>& integrator_names() {
  static const std::vector<std::string> names = {integrator_name(Integrator::EXPLICIT),
                                                 integrator_name(Integrator::IMEX),
                                                 integrator_name(Integrator::IMEX_CONTACT)};
  return names;
}

Integrator parse_integrator(const std::string& name) {
  const std::vector<std::string>& names = integrator_names();
  for (size_t k = 0; k < names.size(); ++k)
    if (name == names[k]) return static_cast<Integrator>(k);
  throw std::invalid_argument("expected \"explicit\", \"imex\" or \"imex-contact\", got \"" + name +
                              "\"");
}

}  // namespace knit
