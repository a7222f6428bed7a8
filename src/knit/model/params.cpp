#include "knit/model/params.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <type_traits>

namespace knit {

namespace {

template <typename T>
constexpr ParamType param_type() {
  if constexpr (std::is_same_v<T, bool>)
    return ParamType::BOOLEAN;
  else if constexpr (std::is_enum_v<T>)
    return ParamType::CHOICE;
  else if constexpr (std::is_integral_v<T>)
    return ParamType::INTEGER;
  else
    return ParamType::REAL;
}

template <typename T>
T from_double(double v) {
  if constexpr (std::is_same_v<T, bool>)
    return v != 0;
  else if constexpr (std::is_enum_v<T>)
    return static_cast<T>(static_cast<int>(v));
  else
    return static_cast<T>(v);
}

const std::vector<std::string> NO_CHOICES;

}  // namespace

const std::vector<ParamDecl>& param_table() {
#define KNIT_PARAM_DECL(group, type, name, def, lo, hi, unit, doc)             \
  ParamDecl{#name,                                                             \
            #group,                                                            \
            param_type<type>(),                                                \
            static_cast<double>(lo),                                           \
            static_cast<double>(hi),                                           \
            unit,                                                              \
            doc,                                                               \
            [](const Params& p) { return static_cast<double>(p.group.name); }, \
            [](Params& p, double v) { p.group.name = from_double<type>(v); }},
  static const std::vector<ParamDecl> table = {
#define KNIT_MATERIAL(type, name, def, lo, hi, unit, doc) \
  KNIT_PARAM_DECL(material, type, name, def, lo, hi, unit, doc)
#define KNIT_DISCRETISATION(type, name, def, lo, hi, unit, doc) \
  KNIT_PARAM_DECL(discretisation, type, name, def, lo, hi, unit, doc)
#define KNIT_SOLVER(type, name, def, lo, hi, unit, doc) \
  KNIT_PARAM_DECL(solver, type, name, def, lo, hi, unit, doc)
#include "knit/model/params.def"
  };
#undef KNIT_PARAM_DECL
  return table;
}

const ParamDecl& param_decl(const std::string& name) {
  for (const ParamDecl& d : param_table())
    if (name == d.name) return d;
  throw std::out_of_range("no parameter named " + name);
}

const std::vector<std::string>& ParamDecl::choices() const {
  // the one choice today: the integrator
  return type == ParamType::CHOICE ? integrator_names() : NO_CHOICES;
}

std::string ParamDecl::text(const Params& p) const {
  const double v = get(p);
  switch (type) {
    case ParamType::BOOLEAN:
      return v != 0 ? "true" : "false";
    case ParamType::CHOICE:
      return choices().at(static_cast<size_t>(v));
    case ParamType::INTEGER:
      return std::to_string(static_cast<long long>(v));
    case ParamType::REAL:
      break;
  }
  return short_number(v);
}

std::string ParamDecl::default_text() const {
  return text(Params{});
}

std::string ParamDecl::option() const {
  std::string o = std::string("--") + name;
  std::replace(o.begin(), o.end(), '_', '-');
  return o;
}

nlohmann::json param_json(const ParamDecl& d, const Params& p) {
  switch (d.type) {
    case ParamType::INTEGER:
      return static_cast<long long>(d.get(p));
    case ParamType::BOOLEAN:
      return d.get(p) != 0;
    case ParamType::CHOICE:
      return d.text(p);
    case ParamType::REAL:
      break;
  }
  return d.get(p);
}

ParamRange param_range(const std::string& name) {
  const ParamDecl& d = param_decl(name);
  if (d.type == ParamType::BOOLEAN || d.type == ParamType::CHOICE)
    throw std::out_of_range(name + " is not a number: it has no range");
  return {d.name, d.min, d.max, d.unit};
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
  const ParamRange r = param_range(name);
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
  for (const ParamDecl& d : param_table())
    if (d.type == ParamType::REAL || d.type == ParamType::INTEGER) check_param(d.name, d.get(p));
  if (p.discretisation.quadrature_points % 2 == 0)
    throw std::invalid_argument(
        "quadrature_points = " + std::to_string(p.discretisation.quadrature_points) +
        " must be odd (Simpson's rule)");
  if (p.solver.contact_reuse > 0 && p.solver.integrator != Integrator::IMEX_CONTACT)
    throw std::invalid_argument("contact_reuse = " + short_number(p.solver.contact_reuse) +
                                " needs the imex-contact integrator (its contact stiffness is "
                                "the linearisation reused)");
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
