// µs per segment-step of stockinette swatches from ~1,000 to ~64,000 segments (square-ish
// samples, 20 contact points): cost should grow linearly with size. Reports the
// least-squares slope of ms/step against segments and the spread of µs/segment-step.
//   bench_scaling [--contact-points N] [--steps N] [--threads N] [--max-segments N]
#include <CLI/CLI.hpp>
#include <iostream>

#include "bench_util.hpp"

int main(int argc, char** argv) {
  int points = 20, steps = 5, threads = 0, max_segments = 70000;
  CLI::App app{"bench_scaling: µs per segment-step from ~1k to ~64k segments"};
  app.add_option("--contact-points", points);
  app.add_option("--steps", steps);
  app.add_option("--threads", threads, "0 = all cores");
  app.add_option("--max-segments", max_segments);
  CLI11_PARSE(app, argc, argv);
  std::unique_ptr<tbb::global_control> gc;
  if (threads > 0)
    gc = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               threads);
  const std::vector<std::pair<int, int>> sizes = {{12, 11}, {24, 22}, {42, 32}, {64, 64}, {90, 90}};
  nlohmann::json runs = nlohmann::json::array();
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (auto [rows, cols] : sizes) {
    if (rows * cols * 8 > max_segments) break;
    knit::bench::StepSetup s = knit::bench::make_step_setup("stockinette", rows, cols, points);
    nlohmann::json r = knit::bench::time_steps(s, 2, steps, 1.0 / 11800);
    r["rows"] = rows;
    r["cols"] = cols;
    const double x = r["segments"].get<double>(), y = r["ms_per_step"].get<double>();
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++n;
    runs.push_back(r);
    std::cerr << "scaling: " << x << " segments: " << r["us_per_segment_step"].get<double>()
              << " us/segment-step\n";
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const double intercept = (sy - slope * sx) / n;
  std::cout << nlohmann::json{{"benchmark", "scaling"},
                              {"contact_points_per_segment", points},
                              {"threads", knit::bench::active_threads()},
                              {"runs", runs},
                              {"slope_us_per_segment_step", 1e3 * slope},
                              {"intercept_ms_per_step", intercept},
                              {"machine", knit::bench::machine_info()}}
                   .dump(2)
            << "\n";
}
