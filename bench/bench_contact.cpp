// Times one evaluation of the contact term (ContactTerm, BVH culling) on a knit-like sample
// of interlocking loops (knit_like_sample, squeeze 0.9: loops pressed into contact).
//
//   bench_contact [segments=11264] [points_per_segment=10] [threads=1] [evaluations=11]
//
// Prints one JSON document: sizes, culling counts, stage times of the median evaluation
// and the CPU model. Evaluations keep the candidate list; refit and traverse times, and
// evaluation_with_list_rebuild_ms, are those of evaluations that rebuild it. The BVH build happens
// once, on a first evaluation that is not timed with the others.
#include <tbb/global_control.h>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "bench_util.hpp"
#include "knit/contact/contact_samples.hpp"
#include "knit/contact/contact_term.hpp"

namespace {

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(colon + 2);
    }
  return "unknown";
}

using knit::bench::median;
using knit::bench::process_cpu_s;

int arg(int argc, char** argv, int k, int fallback) {
  if (argc <= k) return fallback;
  const int value = std::stoi(argv[k]);
  if (value < 1)
    throw std::invalid_argument(std::string("argument ") + argv[k] + " must be positive");
  return value;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const int segments = arg(argc, argv, 1, 11264);
    const int points = arg(argc, argv, 2, 10);
    const int threads = arg(argc, argv, 3, 1);
    const int evaluations = arg(argc, argv, 4, 11);
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);

    // a fabric about as tall as wide: 8 segments per loop, rows ≈ 1.4 × loops per row
    const int loops = std::max(1, (segments + 7) / 8);
    const int per_row = std::max(1, static_cast<int>(std::lround(std::sqrt(loops / 1.4))));
    const int rows = std::max(1, (loops + per_row - 1) / per_row);
    knit::Params params;
    params.discretisation.contact_points = points;
    const knit::ModelBuilder builder =
        knit::knit_like_sample(rows, per_row, 8, params.material.radius, 0.9);
    const knit::Model model = builder.build(params);
    const Eigen::VectorXd q = builder.positions();
    // small random velocities so that the contact damping is evaluated too
    std::mt19937 rng(7);
    std::normal_distribution<double> normal(0.0, 1.0);
    Eigen::VectorXd v(q.size());
    for (int k = 0; k < v.size(); ++k) v[k] = normal(rng);

    knit::ContactTerm term(model, knit::ContactCulling::BVH);
    Eigen::VectorXd force = Eigen::VectorXd::Zero(q.size());
    double energy = term.add_force(model, q, v, 0.0, force);
    const double build = term.last_timings().build;
    std::vector<double> total, points_t, refit, traverse, kernel, gather, rebuild_total, cpu;
    for (int e = 0; e < evaluations; ++e) {
      // one evaluation with a fresh candidate list (not counted below), then one that
      // keeps it, as a simulation does between rebuilds
      force.setZero();
      term.set_candidate_margin(term.candidate_margin());
      term.add_force(model, q, v, 0.0, force);
      rebuild_total.push_back(term.last_timings().total);
      traverse.push_back(term.last_timings().traverse);
      refit.push_back(term.last_timings().refit);
      force.setZero();
      const double c0 = process_cpu_s();
      energy = term.add_force(model, q, v, 0.0, force);
      cpu.push_back(process_cpu_s() - c0);
      const knit::ContactTimings& t = term.last_timings();
      total.push_back(t.total);
      points_t.push_back(t.points);
      kernel.push_back(t.kernel);
      gather.push_back(t.gather);
    }
    const knit::ContactStats& s = term.last_stats();
    nlohmann::ordered_json out;
    out["sample"] = "knit_like_sample rows=" + std::to_string(rows) +
                    " loops_per_row=" + std::to_string(per_row) + " squeeze=0.9";
    out["segments"] = model.num_seg();
    out["points_per_segment"] = points;
    out["threads"] = threads;
    out["evaluations"] = evaluations;
    out["candidate_segment_pairs"] = s.candidate_segment_pairs;
    out["box_tests"] = s.box_tests;
    out["point_pairs_tested"] = s.point_pairs_tested;
    out["point_pairs_in_contact"] = s.point_pairs_in_contact;
    out["min_distance_ratio"] = s.min_distance_ratio;
    out["energy_erg"] = energy;
    out["build_ms"] = 1e3 * build;
    out["points_ms"] = 1e3 * median(points_t);
    out["refit_ms"] = 1e3 * median(refit);
    out["traverse_ms"] = 1e3 * median(traverse);
    out["force_ms"] = 1e3 * (median(kernel) + median(gather));
    out["kernel_ms"] = 1e3 * median(kernel);
    out["gather_ms"] = 1e3 * median(gather);
    out["evaluation_ms"] = 1e3 * median(total);
    out["evaluation_with_list_rebuild_ms"] = 1e3 * median(rebuild_total);
    out["evaluation_cpu_ms"] = 1e3 * median(cpu);
    out["evaluation_min_ms"] = 1e3 * *std::min_element(total.begin(), total.end());
    out["cpu"] = cpu_model();
    std::cout << out.dump(2) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_contact: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
