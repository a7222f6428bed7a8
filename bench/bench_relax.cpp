// Wall time to relax a knitted sample to rest (default 42×32 stockinette, relaxation
// parameters of MODEL.md §8, 10 contact points) and the steps taken.
//   bench_relax [--pattern P] [--rows R] [--cols C] [--max-time S] [--threads N]
#include <CLI/CLI.hpp>
#include <iostream>

#include "bench_util.hpp"
#include "knit/solver/relaxation.hpp"

int main(int argc, char** argv) {
  std::string pattern = "stockinette";
  int rows = 42, cols = 32, threads = 0;
  double max_time = 2.0;
  CLI::App app{"bench_relax: wall time to relax a knitted sample"};
  app.add_option("--pattern", pattern);
  app.add_option("--rows", rows);
  app.add_option("--cols", cols);
  app.add_option("--max-time", max_time, "simulated seconds");
  app.add_option("--threads", threads, "0 = all cores");
  CLI11_PARSE(app, argc, argv);
  const auto thread_cap = knit::bench::limit_threads(threads);
  knit::KnitOptions ko;
  ko.rows = rows;
  ko.cols = cols;
  const knit::GeneratedKnit knit = knit::generate_knit(knit::load_pattern(pattern), ko);
  knit::Params p = knit::Params::relaxation();
  p.gravity.setZero();
  p.k_global = knit::RELAX_K_GLOBAL;  // as `knitsim relax` runs a pattern
  const knit::Model model = knit::build_knit_model(knit, p, knit::RELAX_SHRINK, 0.05);
  knit::Simulator sim(model);
  sim.add_filter(
      std::make_unique<knit::NonRigidDampingFilter>(model, p.alpha_small, p.alpha_large));
  knit::State state;
  state.q =
      Eigen::Map<const Eigen::VectorXd>(knit.control_points.data(), knit.control_points.size());
  state.v = Eigen::VectorXd::Zero(state.q.size());
  knit::RelaxOptions ro;
  ro.max_time = max_time;
  ro.check_every = 1180;
  ro.out_dir = "/tmp/knitsim_bench_relax";
  ro.progress = false;
  ro.write_frames = false;
  const knit::RunReport r = knit::relax(sim, state, ro);
  nlohmann::json out = {{"benchmark", "relax"},
                        {"pattern", pattern},
                        {"rows", rows},
                        {"cols", cols},
                        {"segments", model.num_seg()},
                        {"k_global", p.k_global},
                        {"threads", knit::bench::active_threads()},
                        {"status", r.summary["status"]},
                        {"relaxed", r.summary["relaxed"]},
                        {"steps", r.steps},
                        {"sim_time_s", r.summary["sim_time_s"]},
                        {"wall_time_s", r.summary["wall_time_s"]},
                        {"us_per_segment_step", r.summary["us_per_segment_step"]},
                        {"stage_seconds", r.summary["stage_seconds"]},
                        {"machine", knit::bench::machine_info()}};
  std::cout << out.dump(2) << "\n";
}
