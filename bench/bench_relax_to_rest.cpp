// Time to rest: relaxes knitted samples from their generated yarn with each relaxation
// method asked and reports, per run, the wall time, the simulated time, whether and by
// which test it came to rest, the potential energy, the force residual and the rest
// shape (lengths along the fabric, gauge, extents, edge curl), with its difference from
// the first method's run of the same pattern and, with --reference DIR, from the long
// relaxation kept as the reference in DIR/PATTERN (scripts/relax_reference.sh writes
// out/ref/rest; knit/analysis/rest_reference.hpp says what is compared).
//   bench_relax_to_rest [--patterns stockinette,garter,rib2x2] [--rows R] [--cols C]
//                       [--methods dynamic:explicit:8.474576271186441e-05,fire:imex:3e-4,
//                                  fire:imex-contact:6e-4,fire:imex-contact:6e-4:0.05]
//                       [--max-time S] [--check-every N] [--threads N]
//                       [--reference DIR]
// A method is KIND:INTEGRATOR:H[:REUSE[:WIDEN]] — KIND dynamic (damped dynamics, the
// kinetic-energy rest test unless --residual is given) or fire (FIRE minimisation, the
// force-residual test), INTEGRATOR explicit, imex or imex-contact, H the time step (s), and
// with imex-contact REUSE the contact reuse distance in yarn radii
// (SolverSettings::contact_reuse) and WIDEN the factor it widens by far from rest
// (RelaxOptions::contact_reuse_widen, with its default residual).
#include <CLI/CLI.hpp>
#include <iostream>
#include <map>

#include "bench_util.hpp"
#include "knit/analysis/rest_reference.hpp"
#include "knit/recipes/relax_knit.hpp"

namespace {

struct Method {
  bool fire = false;
  knit::Integrator integrator = knit::Integrator::EXPLICIT;
  double h = 0;
  double contact_reuse = 0;
  double widen = 1;
  std::string text;
};

Method parse_method(const std::string& text) {
  const auto parts = knit::bench::split_list(text, ':');
  if (parts.size() < 3 || parts.size() > 5 || (parts[0] != "dynamic" && parts[0] != "fire"))
    throw std::invalid_argument("'" + text +
                                "': expected KIND:INTEGRATOR:H[:REUSE[:WIDEN]], KIND dynamic or "
                                "fire (e.g. fire:imex:3e-4 or fire:imex-contact:6e-4:0.05:2)");
  return {parts[0] == "fire",
          knit::parse_integrator(parts[1]),
          std::stod(parts[2]),
          parts.size() >= 4 ? std::stod(parts[3]) : 0.0,
          parts.size() == 5 ? std::stod(parts[4]) : 1.0,
          text};
}

}  // namespace

int main(int argc, char** argv) {
  std::string patterns_text = "stockinette,garter,rib2x2";
  std::string methods_text =
      "dynamic:explicit:8.474576271186441e-05,dynamic:imex:3e-4,fire:imex:3e-4,"
      "fire:imex-contact:6e-4,fire:imex-contact:6e-4:0.05";
  int rows = 12, cols = 12, threads = 0, check_every = 0;
  double max_time = 30, residual = 0;
  std::string reference_dir;
  CLI::App app{"bench_relax_to_rest: wall time to relax knitted samples to rest, by method"};
  app.add_option("--patterns", patterns_text, "comma-separated patterns");
  app.add_option("--rows", rows);
  app.add_option("--cols", cols);
  app.add_option("--methods", methods_text, "comma-separated KIND:INTEGRATOR:H[:REUSE[:WIDEN]]");
  app.add_option("--max-time", max_time, "simulated seconds at most per run");
  app.add_option("--residual", residual,
                 "force-residual rest threshold for every method (cm/s²; 0: the kinetic-energy "
                 "test for dynamic runs, the default for fire)");
  app.add_option("--check-every", check_every,
                 "steps between rest checks (0: every 0.015 simulated s)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--reference", reference_dir,
                 "compare each rest shape with DIR/PATTERN/summary.json, a `knitsim relax` run "
                 "of the same size at rest (scripts/relax_reference.sh writes out/ref/rest)");
  app.add_option("--threads", threads, "0 = all cores");
  CLI11_PARSE(app, argc, argv);
  const auto thread_cap = knit::bench::limit_threads(threads);
  std::vector<Method> methods;
  for (const std::string& t : knit::bench::split_list(methods_text))
    methods.push_back(parse_method(t));
  // every reference read before the first run: a missing one fails at once
  std::map<std::string, nlohmann::json> references;
  if (!reference_dir.empty()) {
    try {
      for (const std::string& pattern : knit::bench::split_list(patterns_text))
        references[pattern] = knit::read_rest_reference(reference_dir, pattern, rows, cols);
    } catch (const std::exception& e) {
      std::cerr << "bench_relax_to_rest: --reference: " << e.what() << "\n";
      return 1;
    }
  }

  nlohmann::json runs = nlohmann::json::array();
  for (const std::string& pattern : knit::bench::split_list(patterns_text)) {
    nlohmann::json first;
    for (const Method& m : methods) {
      knit::RelaxKnitOptions o;  // as `knitsim relax PATTERN` runs it
      o.knit.rows = rows;
      o.knit.cols = cols;
      o.fire = m.fire;
      o.params.solver.integrator = m.integrator;
      o.params.solver.time_step = m.h;
      o.params.solver.contact_reuse = m.contact_reuse;
      o.run.contact_reuse_widen = m.widen;
      o.run.max_time = max_time;
      o.run.force_residual = residual;
      o.run.check_every =
          check_every > 0 ? check_every : std::max(1, static_cast<int>(std::lround(0.015 / m.h)));
      o.run.progress = false;  // and no out_dir: nothing written
      const knit::RelaxResult r = knit::relax_knit(pattern, o);
      const nlohmann::json& s = r.report.summary;
      nlohmann::json j = {
          {"pattern", pattern},
          {"method", m.text},
          {"segments", r.model.num_seg()},
          {"status", s["status"]},
          {"relaxed", s["relaxed"]},
          {"rest_test", s["rest_test"]},
          {"steps", r.report.steps},
          {"sim_time_s", s["sim_time_s"]},
          {"wall_time_s", s["wall_time_s"]},
          {"potential_energy", s["potential_energy"]},
          {"ke_per_length", s["ke_per_length"]},
          {"force_residual", s["force_residual"]},
          {"contact_linearised_fraction", s.value("contact_linearised_fraction", nlohmann::json())},
          {"matrix_kept_fraction", s.value("matrix_kept_fraction", nlohmann::json())},
          {"contact_reuse_scale_mean", s.value("contact_reuse_scale_mean", nlohmann::json())},
          {"stage_seconds", s["stage_seconds"]}};
      for (const char* key : knit::REST_SHAPE_KEYS) j[key] = s.value(key, nlohmann::json());
      if (first.is_null()) {
        first = j;
      } else {
        j["relative_difference_from_first"] = knit::compare_rest_shape(j, first);
      }
      if (references.count(pattern)) {
        j["relative_difference_from_reference"] = knit::compare_rest_shape(j, references[pattern]);
        j["reference"] = reference_dir + "/" + pattern;
      }
      std::cerr << "relax_to_rest: " << pattern << " " << m.text << ": " << j["wall_time_s"]
                << " s wall, " << j["sim_time_s"] << " s simulated, "
                << (j["relaxed"].get<bool>() ? "at rest" : "not at rest") << ", PE "
                << j["potential_energy"] << " erg";
      if (j.contains("relative_difference_from_reference"))
        std::cerr << ", width/height/gauge within "
                  << 100 * j["relative_difference_from_reference"]["max_abs_width_height_gauge"]
                               .get<double>()
                  << " % of the reference";
      std::cerr << "\n";
      runs.push_back(j);
    }
  }
  nlohmann::json out = {{"benchmark", "relax_to_rest"},
                        {"rows", rows},
                        {"cols", cols},
                        {"max_time_s", max_time},
                        {"threads", knit::bench::active_threads()},
                        {"machine", knit::bench::machine_info()},
                        {"runs", runs}};
  std::cout << out.dump(2) << "\n";
}
