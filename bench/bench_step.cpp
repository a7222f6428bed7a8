// Full simulation steps on a knitted sample (default: the relaxed 42×32 stockinette in
// examples/knits, 20 contact points per segment, h = 1/11800 s, simulation parameters):
// µs per segment-step and the split by stage as in the paper's Table 2.
//   bench_step [--state relaxed.kstate] [--pattern P] [--rows R] [--cols C]
//              [--contact-points N] [--steps N] [--threads N] [--yarn-friction MU]
// (--yarn-friction adds the yarn–yarn friction filter, its stage "yarn_friction")
#include <CLI/CLI.hpp>
#include <iostream>

#include "bench_util.hpp"

int main(int argc, char** argv) {
  std::string state = knit::bench::default_relaxed_state(), pattern = "stockinette";
  int rows = 42, cols = 32, points = 20, steps = 20, threads = 0;
  double friction = 0;
  CLI::App app{"bench_step: full simulation steps on a knitted sample"};
  app.add_option("--state", state,
                 "relaxed .kstate written by `knitsim relax` (default: the relaxed 42x32 "
                 "stockinette in examples/knits; \"\" for generated geometry of --pattern, --rows, "
                 "--cols)");
  app.add_option("--pattern", pattern);
  app.add_option("--rows", rows);
  app.add_option("--cols", cols);
  app.add_option("--contact-points", points);
  app.add_option("--steps", steps);
  app.add_option("--threads", threads, "0 = all cores");
  app.add_option("--yarn-friction", friction, "yarn–yarn friction coefficient (0: none)");
  CLI11_PARSE(app, argc, argv);
  const auto thread_cap = knit::bench::limit_threads(threads);
  knit::bench::StepSetup s =
      knit::bench::make_step_setup(pattern, rows, cols, points, state, friction);
  nlohmann::json out = knit::bench::time_steps(s, 3, steps, 1.0 / 11800);
  out["benchmark"] = "step";
  out["pattern"] = s.pattern;
  out["rows"] = s.rows;
  out["cols"] = s.cols;
  out["yarn_friction"] = friction;
  out["relaxed_state"] = s.relaxed ? state : "none (generated geometry)";
  out["machine"] = knit::bench::machine_info();
  std::cout << out.dump(2) << "\n";
}
