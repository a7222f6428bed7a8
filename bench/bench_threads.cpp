// The step benchmark on 1 and on 2 threads (or --max-threads): speed-up and parallel
// efficiency.   bench_threads [--state relaxed.kstate] [--rows R] [--cols C] [--steps N]
#include <iostream>

#include "bench_util.hpp"

int main(int argc, char** argv) {
  std::string state;
  int rows = 42, cols = 32, points = 20, steps = 10, max_threads = 2;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--state")
      state = v;
    else if (a == "--rows")
      rows = std::stoi(v);
    else if (a == "--cols")
      cols = std::stoi(v);
    else if (a == "--contact-points")
      points = std::stoi(v);
    else if (a == "--steps")
      steps = std::stoi(v);
    else if (a == "--max-threads")
      max_threads = std::stoi(v);
    else {
      std::cerr << "bench_threads: unknown option " << a << "\n";
      return 1;
    }
  }
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
