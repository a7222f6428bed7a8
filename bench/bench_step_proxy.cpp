// Times the whole simulation step (Simulator::step: two force evaluations, projection,
// filters) on a knit-like sample of interlocking loops (knit_like_sample, squeeze 0.9) as
// a proxy for the relaxed 42×32 stockinette of the paper's stretch tests (MODEL.md §9):
// simulation parameters, length constraints on, gravity 0, nothing pinned, from rest.
//
//   bench_step_proxy [segments=11264[,…]] [points_per_segment=20] [threads=1[,…]] [steps=10]
//                    [margin_radii=default]
//
// Comma-separated lists run every combination (e.g. "2000,8000,32000,64000" and "1,2").
// Every run starts from the same state, so every thread count simulates the same
// trajectory. Two untimed warm-up steps build the BVH and the projection's symbolic
// factorisation. Prints one JSON document: per run the median step (wall clock, and the
// CPU time of all threads, which a shared machine inflates less), µs per segment-step,
// seconds per stage per step, heap allocations per step (operator new is counted),
// contact point pairs per step, projection iterations, CPU.
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <time.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include "bench_util.hpp"
#include "knit/contact/contact_samples.hpp"
#include "knit/contact/contact_term.hpp"
#include "knit/solver/simulator.hpp"
#include "knit/solver/terms.hpp"

// every heap allocation of this program is counted, to report allocations per step
// (GCC 12 warns falsely that free() does not match these operator new replacements)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
static std::atomic<long long> g_allocations{0};
void* operator new(std::size_t size) {
  ++g_allocations;
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void* operator new(std::size_t size, std::align_val_t align) {
  ++g_allocations;
  const std::size_t a = static_cast<std::size_t>(align);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size, std::align_val_t align) {
  return operator new(size, align);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}

namespace {

std::vector<int> int_list(int argc, char** argv, int k, const std::vector<int>& fallback) {
  if (argc <= k) return fallback;
  std::vector<int> out;
  std::stringstream in(argv[k]);
  for (std::string item; std::getline(in, item, ',');) {
    const int value = std::stoi(item);
    if (value < 1)
      throw std::invalid_argument(std::string("argument ") + argv[k] + " must be positive");
    out.push_back(value);
  }
  return out;
}

using knit::bench::median;
using knit::bench::process_cpu_s;

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::vector<int> sizes = int_list(argc, argv, 1, {11264});
    const int points = int_list(argc, argv, 2, {20}).front();
    const std::vector<int> thread_counts = int_list(argc, argv, 3, {1});
    const int steps = int_list(argc, argv, 4, {10}).front();
    const double h = 1.0 / 11800;
    const double margin_radii =
        argc > 5 ? std::stod(argv[5]) : knit::ContactTerm::DEFAULT_MARGIN_RADII;

    nlohmann::ordered_json out;
    out["machine"] = knit::bench::machine_info();
    out["time_step_s"] = h;
    out["steps"] = steps;
    out["runs"] = nlohmann::json::array();
    for (const int segments : sizes) {
      // a fabric about as tall as wide: 8 segments per loop, rows ≈ 1.4 × loops per row
      const int loops = std::max(1, (segments + 7) / 8);
      const int per_row = std::max(1, static_cast<int>(std::lround(std::sqrt(loops / 1.4))));
      const int rows = std::max(1, (loops + per_row - 1) / per_row);
      knit::Params params = knit::Params::simulation();
      params.discretisation.contact_points = points;
      params.gravity.setZero();
      const knit::ModelBuilder builder =
          knit::knit_like_sample(rows, per_row, 8, params.material.radius, 0.9);
      const knit::Model model = builder.build(params);
      knit::State start;
      start.q = builder.positions();
      start.v = Eigen::VectorXd::Zero(start.q.size());

      for (const int threads : thread_counts) {
        // an explicit arena per run: the main thread's implicit arena keeps the concurrency
        // of its first use, so a global_control alone would not raise 1 thread to 2
        tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);
        tbb::task_arena arena(threads);
        arena.execute([&] {
          // the contact term is built here to set its candidate margin (a knob of this
          // benchmark); everything measured is read from the step data
          auto terms = knit::default_terms(model);
          knit::ContactTerm* contact = nullptr;
          for (auto& t : terms)
            if (t->name() == "contact") contact = static_cast<knit::ContactTerm*>(t.get());
          knit::Simulator sim(model, std::move(terms));
          if (contact) contact->set_candidate_margin(margin_radii * params.material.radius);
          knit::State state = start;
          for (int k = 0; k < 2; ++k)
            if (!sim.step(state, h).ok()) throw std::runtime_error("warm-up step failed");
          sim.reset_timings();
          const long long evals0 = contact ? contact->evaluations() : 0;
          const long long rebuilds0 = contact ? contact->candidate_rebuilds() : 0;
          std::vector<double> step_s, cpu_s;
          long long allocations = 0;
          double contact_pairs = 0, candidates = 0, iterations = 0;
          int max_iterations = 0;
          for (int k = 0; k < steps; ++k) {
            const double t0 = knit::bench::now_s(), c0 = process_cpu_s();
            const long long a0 = g_allocations.load();
            const knit::StepResult res = sim.step(state, h);
            allocations += g_allocations.load() - a0;
            step_s.push_back(knit::bench::now_s() - t0);
            cpu_s.push_back(process_cpu_s() - c0);
            if (!res.ok()) throw std::runtime_error("step failed: " + res.message);
            iterations += res.projection.iterations;
            max_iterations = std::max(max_iterations, res.projection.iterations);
            contact_pairs += sim.data().contact.point_pairs_in_contact;
            candidates += sim.data().contact.candidate_segment_pairs;
          }
          double total = 0;
          for (double s : step_s) total += s;
          const double med = median(step_s);
          nlohmann::ordered_json run;
          run["sample"] = "knit_like_sample rows=" + std::to_string(rows) +
                          " loops_per_row=" + std::to_string(per_row) + " squeeze=0.9";
          run["segments"] = model.num_seg();
          run["points_per_segment"] = points;
          run["threads"] = threads;
          run["step_ms_median"] = 1e3 * med;
          run["step_ms_min"] = 1e3 * *std::min_element(step_s.begin(), step_s.end());
          run["us_per_segment_step"] = 1e6 * med / model.num_seg();
          // CPU time of all threads per step: with 1 thread, the step time on an idle core
          run["cpu_ms_per_step_median"] = 1e3 * median(cpu_s);
          nlohmann::ordered_json stages;
          for (const auto& [name, seconds] : sim.data().stage_seconds)
            stages[name] = 1e3 * seconds / steps;
          run["stage_ms_per_step"] = stages;
          run["other_ms_per_step"] = [&] {
            double staged = 0;
            for (const auto& [name, seconds] : sim.data().stage_seconds) staged += seconds;
            return 1e3 * (total - staged) / steps;
          }();
          run["heap_allocations_per_step"] = double(allocations) / steps;
          run["contact_point_pairs_per_evaluation"] = contact_pairs / steps;
          run["candidate_segment_pairs_per_evaluation"] = candidates / steps;
          if (contact) {
            run["contact_candidate_margin_cm"] = contact->candidate_margin();
            run["contact_list_rebuilds_per_evaluation"] =
                double(contact->candidate_rebuilds() - rebuilds0) /
                double(std::max(1LL, contact->evaluations() - evals0));
          }
          run["projection_iterations_mean"] = iterations / steps;
          run["projection_iterations_max"] = max_iterations;
          out["runs"].push_back(run);
        });
      }
    }
    std::cout << out.dump(2) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_step_proxy: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
