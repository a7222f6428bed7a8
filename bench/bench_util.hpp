#pragma once
// Shared helpers for knitsim's benchmarks: machine facts and timing. Every benchmark
// prints one JSON document on stdout.
#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace knit::bench {

/// The non-empty items of a comma-separated list ("a,b,,c" → a, b, c).
inline std::vector<std::string> split_list(const std::string& text, char separator = ',') {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, separator);)
    if (!item.empty()) out.push_back(item);
  return out;
}

inline nlohmann::json machine_info() {
  std::string model = "unknown";
  std::ifstream cpu("/proc/cpuinfo");
  for (std::string line; std::getline(cpu, line);)
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  char host[256] = {0};
  gethostname(host, sizeof host - 1);
  return {{"cpu_model", model},
          {"hardware_threads", std::thread::hardware_concurrency()},
          {"host", host},
#ifdef NDEBUG
          {"build", "release"}
#else
          {"build", "debug"}
#endif
  };
}

/// Caps TBB's worker threads at `threads` while the returned object lives (0 = no cap).
inline std::unique_ptr<tbb::global_control> limit_threads(int threads) {
  if (threads <= 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               threads);
}

/// Worker threads in force here: the current arena's size, capped by any global_control.
inline int active_threads() {
  return static_cast<int>(std::min<size_t>(
      tbb::this_task_arena::max_concurrency(),
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)));
}

/// CPU seconds used by the whole process (all threads): unlike wall time, it does not
/// count time spent descheduled on a shared machine.
inline double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/// The median (upper median for an even count).
inline double median(std::vector<double> x) {
  std::sort(x.begin(), x.end());
  return x[x.size() / 2];
}

inline double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace knit::bench

#include <memory>

#include "knit/filters/nonrigid_damping.hpp"
#include "knit/filters/yarn_friction.hpp"
#include "knit/io/state_file.hpp"
#include "knit/pattern/generator.hpp"
#include "knit/pattern/pattern.hpp"
#include "knit/recipes/simulate_scene.hpp"
#include "knit/scene/scene.hpp"
#include "knit/solver/simulator.hpp"

namespace knit::bench {

/// A knitted sample ready to step with the simulation parameters (MODEL.md §8), length
/// constraints on, non-rigid damping on, gravity on: a relaxed knit read from `state_path`
/// (a .kstate written by `knitsim relax`, placed as a scene places it), or, without one,
/// the generated yarn of `pattern` at rows × cols with rest lengths from that geometry.
/// The relaxed 42×32 stockinette kept in the repository: the default sample of the step
/// benchmarks (a relaxed sample has about 2.5× the contact pairs of generated geometry).
inline std::string default_relaxed_state() {
  return std::string(KNIT_EXAMPLES) + "/knits/stockinette_42x32.kstate";
}

struct StepSetup {
  std::unique_ptr<Simulator> sim;
  State state;
  bool relaxed = false;
  int rows = 0, cols = 0;
  std::string pattern;
};

inline StepSetup make_step_setup(const std::string& pattern, int rows, int cols, int contact_points,
                                 const std::string& state_path = "", double yarn_friction = 0) {
  Params p = Params::simulation();
  p.discretisation.contact_points = contact_points;
  p.material.yarn_friction = yarn_friction;
  StepSetup s;
  s.pattern = pattern;
  s.rows = rows;
  s.cols = cols;
  if (!state_path.empty()) {
    Scene scene = scene_from_knit_state(state_path, p);
    s.sim = make_scene_simulator(scene);
    s.state = scene.state;
    s.relaxed = true;
    const StateFile f = read_state_file(state_path);
    if (f.knit) {
      s.pattern = f.knit->pattern;
      s.rows = f.knit->rows;
      s.cols = f.knit->cols;
    }
  } else {
    KnitOptions ko;
    ko.rows = rows;
    ko.cols = cols;
    const GeneratedKnit knit = generate_knit(load_pattern(pattern), ko);
    const Model model = build_knit_model(knit, p);
    s.sim = std::make_unique<Simulator>(model);
    s.sim->add_filter(std::make_unique<NonRigidDampingFilter>(model, p.material.alpha_small,
                                                              p.material.alpha_large));
    if (yarn_friction > 0) s.sim->add_filter(std::make_unique<YarnFrictionFilter>(yarn_friction));
    s.state.q =
        Eigen::Map<const Eigen::VectorXd>(knit.control_points.data(), knit.control_points.size());
    s.state.v = Eigen::VectorXd::Zero(s.state.q.size());
  }
  s.sim->satisfy_constraints(s.state);
  return s;
}

/// Steps `steps` times (after `warmup` untimed steps) and returns timings as JSON:
/// us_per_segment_step, ms_per_step, seconds per stage, contact pairs per step — all read
/// from the simulator's step data.
inline nlohmann::json time_steps(StepSetup& s, int warmup, int steps, double h) {
  Simulator& sim = *s.sim;
  for (int i = 0; i < warmup; ++i)
    if (!sim.step(s.state, h).ok()) throw std::runtime_error("warm-up step failed");
  sim.reset_timings();
  const StepData& data = sim.data();
  double pairs = 0;
  int iterations = 0;
  const double t0 = now_s();
  for (int i = 0; i < steps; ++i) {
    const StepResult r = sim.step(s.state, h);
    if (!r.ok()) throw std::runtime_error("step failed: " + r.message);
    iterations += data.projection.iterations;
    pairs += static_cast<double>(data.contact.point_pairs_in_contact);
  }
  const double wall = now_s() - t0;
  const int nseg = sim.model().num_seg();
  nlohmann::json stages = nlohmann::json::object();
  double other = 0;
  for (const auto& [name, sec] : data.stage_seconds) {
    stages[name + "_s_per_step"] = sec / steps;
    if (name != "contact" && name != "projection" && name != "nonrigid_damping" && name != "record")
      other += sec;
  }
  const auto& st = data.stage_seconds;
  auto get = [&](const char* k) { return st.count(k) ? st.at(k) : 0.0; };
  const double total = wall;
  return {{"segments", nseg},
          {"contact_points_per_segment", sim.model().params.discretisation.contact_points},
          {"threads", active_threads()},
          {"steps", steps},
          {"time_step_s", h},
          {"us_per_segment_step", 1e6 * wall / (static_cast<double>(steps) * nseg)},
          {"ms_per_step", 1e3 * wall / steps},
          {"contact_pairs_per_step", pairs / steps},
          {"projection_iterations_per_step", static_cast<double>(iterations) / steps},
          {"split",
           {{"yarn_contact", get("contact") / total},
            {"other_energies", other / total},
            {"constraints", get("projection") / total},
            {"velocity_filters", get("nonrigid_damping") / total},
            {"step_data_records", get("record") / total}}},
          {"stages", stages}};
}

}  // namespace knit::bench
