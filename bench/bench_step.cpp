// Full simulation steps on a knitted sample (default: 42×32 stockinette, 20 contact points
// per segment, h = 1/11800 s, simulation parameters): µs per segment-step and the split by
// stage as in the paper's Table 2.
//   bench_step [--state relaxed.kstate] [--pattern P] [--rows R] [--cols C]
//              [--contact-points N] [--steps N] [--threads N]
#include <iostream>

#include "bench_util.hpp"

int main(int argc, char** argv) {
  std::string state, pattern = "stockinette";
  int rows = 42, cols = 32, points = 20, steps = 20, threads = 0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--state")
      state = v;
    else if (a == "--pattern")
      pattern = v;
    else if (a == "--rows")
      rows = std::stoi(v);
    else if (a == "--cols")
      cols = std::stoi(v);
    else if (a == "--contact-points")
      points = std::stoi(v);
    else if (a == "--steps")
      steps = std::stoi(v);
    else if (a == "--threads")
      threads = std::stoi(v);
    else {
      std::cerr << "bench_step: unknown option " << a << "\n";
      return 1;
    }
  }
  std::unique_ptr<tbb::global_control> gc;
  if (threads > 0)
    gc = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               threads);
  knit::bench::StepSetup s = knit::bench::make_step_setup(pattern, rows, cols, points, state);
  nlohmann::json out = knit::bench::time_steps(s, 3, steps, 1.0 / 11800);
  out["benchmark"] = "step";
  out["pattern"] = pattern;
  out["rows"] = rows;
  out["cols"] = cols;
  out["relaxed_state"] = s.relaxed ? state : "none (generated geometry)";
  out["machine"] = knit::bench::machine_info();
  std::cout << out.dump(2) << "\n";
}
