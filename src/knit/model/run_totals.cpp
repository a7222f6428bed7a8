#include "knit/model/run_totals.hpp"

#include <cmath>
#include <stdexcept>

namespace knit {

namespace {

// Every field of the totals by its name in the state file's run block: the one list that
// writing and reading go through.
template <class Totals, class Field>
void each_field(Totals& t, Field&& f) {
  f("start_time_s", t.start_time);
  f("end_time_s", t.end_time);
  f("steps", t.steps);
  f("shortened_steps_s", t.shortened_steps);
  f("frames_written", t.frames_written);
  f("contact_steps", t.contact_steps);
  f("contact_pairs_sum", t.contact_pairs_sum);
  f("min_contact_distance", t.min_contact_distance);
  f("contact_linearised", t.contact_linearised);
  f("matrix_kept", t.matrix_kept);
  f("reuse_scale_sum", t.reuse_scale_sum);
  f("solve_steps", t.solve_steps);
  f("solve_iterations", t.solve_iterations);
  f("solve_iterations_max", t.solve_iterations_max);
  f("solve_residual_max", t.solve_residual_max);
  f("friction_steps", t.friction_steps);
  f("friction_pairs", t.friction_pairs);
  f("friction_stuck", t.friction_stuck);
  f("friction_passes", t.friction_passes);
  f("friction_passes_max", t.friction_passes_max);
  f("friction_work", t.friction_work);
  f("halving_retried", t.halving.retried);
  f("halving_substeps", t.halving.substeps);
  f("halving_deepest", t.halving.deepest);
  f("halving_level", t.halving.level);
  f("halving_calm", t.halving.calm);
  f("warnings", t.warnings);
  f("objects", t.objects);
  f("crossings", t.crossings);
}

// (an extreme not reached yet is +infinity, which JSON writes as null)
nlohmann::json number(double x) {
  return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
}

struct Writer {
  nlohmann::json& j;
  void operator()(const char* key, double v) { j[key] = number(v); }
  void operator()(const char* key, long long v) { j[key] = v; }
  void operator()(const char* key, int v) { j[key] = v; }
  void operator()(const char* key, const std::vector<double>& v) { j[key] = v; }
  void operator()(const char* key, const std::map<std::string, long long>& m) {
    j[key] = nlohmann::json::object();
    for (const auto& [name, count] : m) j[key][name] = count;
  }
  void operator()(const char* key, const std::map<std::string, RunTotals::Object>& m) {
    j[key] = nlohmann::json::object();
    for (const auto& [name, o] : m)
      j[key][name] = {{"deepest_penetration_cm", number(o.deepest_penetration)},
                      {"contact_points_sum", number(o.contact_points_sum)}};
  }
  void operator()(const char* key, const CrossingTotals& c) {
    j[key] = {{"steps_checked", c.steps_checked},
              {"count", c.count},
              {"first_time_s", number(c.first_time)},
              {"first_segments", {c.first_segment_a, c.first_segment_b}},
              {"first_point_cm", {c.first_x, c.first_y, c.first_z}}};
  }
};

[[noreturn]] void fail(const std::string& key, const std::string& what) {
  throw std::invalid_argument("run." + key + ": " + what);
}

double read_double(const nlohmann::json& v, const std::string& key, bool null_is_infinity) {
  if (null_is_infinity && v.is_null()) return std::numeric_limits<double>::infinity();
  if (!v.is_number() || !std::isfinite(v.get<double>())) fail(key, "not a finite number");
  return v.get<double>();
}

long long read_count(const nlohmann::json& v, const std::string& key, long long max) {
  if (!v.is_number_integer()) fail(key, "not an integer");
  const long long n = v.get<long long>();
  if (n < 0 || n > max) fail(key, std::to_string(n) + " is outside 0 to " + std::to_string(max));
  return n;
}

struct Reader {
  const nlohmann::json& j;
  const nlohmann::json& at(const char* key) const {
    if (!j.contains(key)) fail(key, "missing");
    return j.at(key);
  }
  void operator()(const char* key, double& v) {
    // the closest approach alone is null until a contact is seen
    v = read_double(at(key), key, std::string(key) == "min_contact_distance");
  }
  void operator()(const char* key, long long& v) {
    v = read_count(at(key), key, std::numeric_limits<long long>::max());
  }
  void operator()(const char* key, int& v) {
    v = static_cast<int>(read_count(at(key), key, std::numeric_limits<int>::max()));
  }
  void operator()(const char* key, std::vector<double>& v) {
    const nlohmann::json& a = at(key);
    if (!a.is_array()) fail(key, "not an array");
    v.clear();
    for (size_t i = 0; i < a.size(); ++i)
      v.push_back(read_double(a[i], std::string(key) + "[" + std::to_string(i) + "]", false));
  }
  void operator()(const char* key, std::map<std::string, long long>& m) {
    const nlohmann::json& o = at(key);
    if (!o.is_object()) fail(key, "not an object");
    m.clear();
    for (const auto& [name, count] : o.items())
      m[name] = read_count(count, std::string(key) + "[\"" + name + "\"]",
                           std::numeric_limits<long long>::max());
  }
  void operator()(const char* key, std::map<std::string, RunTotals::Object>& m) {
    const nlohmann::json& o = at(key);
    if (!o.is_object()) fail(key, "not an object");
    m.clear();
    for (const auto& [name, value] : o.items()) {
      const std::string where = std::string(key) + "[\"" + name + "\"]";
      if (!value.is_object()) fail(where, "not an object");
      RunTotals::Object& out = m[name];
      for (auto [field, target] : {std::pair{"deepest_penetration_cm", &out.deepest_penetration},
                                   std::pair{"contact_points_sum", &out.contact_points_sum}}) {
        if (!value.contains(field)) fail(where + "." + field, "missing");
        *target = read_double(value.at(field), where + "." + field, false);
      }
    }
  }
  void operator()(const char* key, CrossingTotals& c) {
    // states written before runs checked crossings have none: nothing was checked
    if (!j.contains(key)) {
      c = CrossingTotals{};
      return;
    }
    const nlohmann::json& o = j.at(key);
    const std::string where(key);
    if (!o.is_object()) fail(where, "not an object");
    auto field = [&](const char* name) -> const nlohmann::json& {
      if (!o.contains(name)) fail(where + "." + name, "missing");
      return o.at(name);
    };
    const long long big = std::numeric_limits<long long>::max();
    c.steps_checked = read_count(field("steps_checked"), where + ".steps_checked", big);
    c.count = read_count(field("count"), where + ".count", big);
    c.first_time = read_double(field("first_time_s"), where + ".first_time_s", true);
    const nlohmann::json& seg = field("first_segments");
    const nlohmann::json& pt = field("first_point_cm");
    if (!seg.is_array() || seg.size() != 2) fail(where + ".first_segments", "not a pair");
    if (!pt.is_array() || pt.size() != 3) fail(where + ".first_point_cm", "not 3 numbers");
    for (int k = 0; k < 2; ++k) {
      const std::string at = where + ".first_segments[" + std::to_string(k) + "]";
      if (!seg[k].is_number_integer()) fail(at, "not an integer");
      const long long s = seg[k].get<long long>();
      if (s < -1 || s > std::numeric_limits<int>::max()) fail(at, "out of range");
      (k == 0 ? c.first_segment_a : c.first_segment_b) = static_cast<int>(s);
    }
    double* xyz[3] = {&c.first_x, &c.first_y, &c.first_z};
    for (int k = 0; k < 3; ++k)
      *xyz[k] = read_double(pt[k], where + ".first_point_cm[" + std::to_string(k) + "]", false);
  }
};

}  // namespace

nlohmann::json to_json(const RunTotals& t) {
  nlohmann::json j = nlohmann::json::object();
  each_field(t, Writer{j});
  return j;
}

RunTotals run_totals_from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw std::invalid_argument("run: not a JSON object");
  RunTotals t;
  each_field(t, Reader{j});
  return t;
}

}  // namespace knit
