// The step benchmark on 1 and on 2 threads (or --max-threads): speed-up and parallel
// efficiency.   bench_threads [--state relaxed.kstate] [--rows R] [--cols C] [--steps N]
#include <CLI/CLI.hpp>
#include <iostream>

#include "bench_util.hpp"

int main(int argc, char** argv) {
  std::string state = knit::bench::default_relaxed_state();
  int rows = 42, cols = 32, points = 20, steps = 10, max_threads = 2;
  CLI::App app{"bench_threads: the step benchmark on 1 and 2 threads"};
  app.add_option("--state", state,
                 "relaxed .kstate (default: the relaxed 42x32 stockinette in examples/knits; "
                 "\"\" for generated geometry)");
  app.add_option("--rows", rows);
  app.add_option("--cols", cols);
  app.add_option("--contact-points", points);
  app.add_option("--steps", steps);
  app.add_option("--max-threads", max_threads);
  CLI11_PARSE(app, argc, argv);
  nlohmann::json runs = nlohmann::json::array();
  double base = 0;
  for (int t = 1; t <= max_threads; t *= 2) {
    // an explicit arena per run: a global_control alone does not resize the implicit arena
    tbb::task_arena arena(t);
    nlohmann::json r;
    arena.execute([&] {
      knit::bench::StepSetup s =
          knit::bench::make_step_setup("stockinette", rows, cols, points, state);
      r = knit::bench::time_steps(s, 3, steps, 1.0 / 11800);
    });
    const double ms = r["ms_per_step"].get<double>();
    if (t == 1) base = ms;
    r["speedup"] = base / ms;
    r["efficiency"] = base / ms / t;
    runs.push_back(r);
  }
  std::cout << nlohmann::json{{"benchmark", "threads"},
                              {"runs", runs},
                              {"machine", knit::bench::machine_info()}}
                   .dump(2)
            << "\n";
}
