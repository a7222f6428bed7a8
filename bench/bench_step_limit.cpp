// What bounds the explicit time step. From a relaxed knit (a .kstate written by
// `knitsim relax`), continues the relaxation as `relax --resume` would, at each time step
// of a list, for a fixed simulated time, with the full model and with one ingredient
// changed at a time (a force term left out, the non-rigid damping filter left out, the
// yarn ends' lumped mass raised). For each (variant, h) it reports whether the run stayed
// stable, the step it failed at, and where: the control point and how far it lies from
// its yarn's nearer end. The variant whose limit moves is what bounds h.
//   bench_step_limit [--state FILE] [--pattern P --rows R --cols C] [--time S]
//                    [--h H1,H2,...] [--variants V1,V2,...] [--threads N]
// Variants: full, no-filter, no-contact, no-bending, no-length, end-mass (the first two
// and last two control points of each yarn get at least half an interior one's mass),
// imex (the full model with the length energy taken implicitly: --integrator imex); join
// them with '+' to change several at once (imex+no-contact); sim-bending gives the yarn the
// simulation's bending stiffness (MODEL.md §8: k_bend 5 against the relaxation's 0.005).
#include <CLI/CLI.hpp>
#include <iostream>
#include <regex>

#include "bench_util.hpp"
#include "knit/filters/nonrigid_damping.hpp"
#include "knit/recipes/relax_knit.hpp"
#include "knit/solver/simulator.hpp"
#include "knit/solver/terms.hpp"

namespace {

struct Outcome {
  bool stable = true;
  long steps = 0;
  int cp = -1;  // failing control point (index in its yarn), −1 when stable
  int from_end = -1;
  std::string message;
  double wall_s = 0;
};

Outcome run(const knit::Model& base, const knit::State& start, const std::string& variant, double h,
            double duration, double alpha_small, double alpha_large, bool round) {
  // a variant is one or more ingredients joined by '+': "imex+no-contact"
  auto has = [&](const std::string& part) {
    return ("+" + variant + "+").find("+" + part + "+") != std::string::npos;
  };
  knit::Model model = base;
  if (has("end-mass")) {  // row-sum lumping gives the ends 1/24 and 1/2 of an interior mass
    model.params.discretisation.end_mass_floor = 0.5;
    knit::apply_end_mass_floor(model, 0.5);
  }
  if (has("imex")) model.params.solver.integrator = knit::Integrator::IMEX;
  if (has("imex-contact")) model.params.solver.integrator = knit::Integrator::IMEX_CONTACT;
  if (has("sim-bending")) model.params.material.k_bend = knit::Params::simulation().material.k_bend;
  std::vector<std::unique_ptr<knit::Term>> terms;
  for (auto& t : knit::default_terms(model)) {
    const std::string name(t->name());
    if ((has("no-contact") && name == "contact") || (has("no-bending") && name == "bending") ||
        (has("no-length") && name == "length"))
      continue;
    terms.push_back(std::move(t));
  }
  knit::Simulator sim(std::move(model), std::move(terms));
  if (!has("no-filter"))
    sim.add_filter(std::make_unique<knit::NonRigidDampingFilter>(sim.model(), alpha_small,
                                                                 alpha_large, round));
  knit::State s = start;
  Outcome o;
  const long steps = static_cast<long>(std::ceil(duration / h - 1e-9));
  const auto t0 = std::chrono::steady_clock::now();
  for (long i = 0; i < steps; ++i) {
    const knit::StepResult r = sim.step(s, h);
    if (!r.ok()) {
      o.stable = false;
      o.steps = i;
      o.message = r.message;
      std::smatch m;
      static const std::regex where("control point ([0-9]+) of yarn ([0-9]+)");
      if (std::regex_search(r.message, m, where)) {
        o.cp = std::stoi(m[1]);
        const int n = sim.model().yarns[std::stoi(m[2])].num_cp();
        o.from_end = std::min(o.cp, n - 1 - o.cp);
      }
      break;
    }
    o.steps = i + 1;
  }
  o.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  std::string state_path = KNIT_EXAMPLES "/knits/stockinette_12x12.kstate";
  std::string pattern = "stockinette", hs = "8.47e-5,1e-4,1.25e-4,1.5e-4,2e-4";
  std::string variants = "full,no-filter,no-contact,no-bending,no-length,end-mass";
  int rows = 12, cols = 12, threads = 0;
  double duration = 0.03;
  CLI::App app{"bench_step_limit: what bounds the explicit time step"};
  app.add_option("--state", state_path, "a relaxed knit (.kstate written by knitsim relax)");
  app.add_option("--pattern", pattern);
  app.add_option("--rows", rows);
  app.add_option("--cols", cols);
  app.add_option("--time", duration, "simulated seconds per run");
  app.add_option("--h", hs, "comma-separated time steps (s)");
  app.add_option("--variants", variants);
  app.add_option("--threads", threads, "0 = all cores");
  CLI11_PARSE(app, argc, argv);
  const auto gc = knit::bench::limit_threads(threads);

  knit::RelaxKnitOptions o;
  o.knit.rows = rows;
  o.knit.cols = cols;
  const knit::State start = knit::read_resumed_knit_state(state_path, pattern, o.knit);
  o.resume = &start;
  knit::KnitRelaxation setup = knit::setup_knit_relaxation(pattern, o);
  const knit::Model& model = setup.sim->model();

  nlohmann::json runs = nlohmann::json::array();
  for (const std::string& v : knit::bench::split_list(variants))
    for (const std::string& hstr : knit::bench::split_list(hs)) {
      const double h = std::stod(hstr);
      const Outcome r = run(model, start, v, h, duration, o.params.material.alpha_small,
                            o.params.material.alpha_large, o.knit.in_the_round);
      std::cerr << "step_limit: " << v << " h=" << h << ": "
                << (r.stable ? "stable"
                             : "unstable after " + std::to_string(r.steps) + " steps at cp " +
                                   std::to_string(r.cp) + " (" + std::to_string(r.from_end) +
                                   " from the end)")
                << "\n";
      runs.push_back({{"variant", v},
                      {"h", h},
                      {"stable", r.stable},
                      {"steps", r.steps},
                      {"failed_cp", r.cp},
                      {"failed_cp_from_end", r.from_end},
                      {"message", r.message},
                      {"wall_s", r.wall_s}});
    }
  nlohmann::json out = {{"benchmark", "step_limit"},
                        {"machine", knit::bench::machine_info()},
                        {"threads", knit::bench::active_threads()},
                        {"state", state_path},
                        {"pattern", pattern},
                        {"rows", rows},
                        {"cols", cols},
                        {"segments", model.num_seg()},
                        {"simulated_s", duration},
                        {"runs", runs}};
  std::cout << out.dump(2) << "\n";
}
