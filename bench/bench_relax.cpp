// Wall time to relax a knitted sample to rest (default 42×32 stockinette, relaxation
// parameters of MODEL.md §8, 10 contact points) and the steps taken.
//   bench_relax [--pattern P] [--rows R] [--cols C] [--max-time S] [--threads N]
#include <CLI/CLI.hpp>
#include <iostream>

#include "bench_util.hpp"
#include "knit/recipes/relax_knit.hpp"

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
  knit::RelaxKnitOptions o;  // as `knitsim relax PATTERN` runs it
  o.knit.rows = rows;
  o.knit.cols = cols;
  o.run.max_time = max_time;
  o.run.check_every = 1180;
  o.run.progress = false;  // and no out_dir: nothing written
  const knit::RelaxResult r = knit::relax_knit(pattern, o);
  nlohmann::json out = {{"benchmark", "relax"},
                        {"pattern", pattern},
                        {"rows", rows},
                        {"cols", cols},
                        {"segments", r.model.num_seg()},
                        {"k_global", o.params.material.k_global},
                        {"threads", knit::bench::active_threads()},
                        {"status", r.report.summary["status"]},
                        {"relaxed", r.report.summary["relaxed"]},
                        {"steps", r.report.steps},
                        {"sim_time_s", r.report.summary["sim_time_s"]},
                        {"wall_time_s", r.report.summary["wall_time_s"]},
                        {"us_per_segment_step", r.report.summary["us_per_segment_step"]},
                        {"stage_seconds", r.report.summary["stage_seconds"]},
                        {"machine", knit::bench::machine_info()}};
  std::cout << out.dump(2) << "\n";
}
