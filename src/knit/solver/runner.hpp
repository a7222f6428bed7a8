#pragma once
// Runs a simulation for a duration, writing states, a CSV log and a JSON summary into an
// output directory (or nothing at all when no directory is given):
//   DIR/frames/state_NNNNNN.kstate   every `output_every` steps (and the initial state)
//   DIR/final.kstate                 the last state (the last good one if the run failed)
//   DIR/log.csv                      time_s, kinetic_energy, potential_energy,
//                                    max_violation, contact_pairs, min_contact_distance,
//                                    wall_s_per_step, energy_<term>…, <group>_fx/fy/fz…
//                                    — one row per written state, appended as the run goes
//   DIR/summary.json                 status, counts, energies, constraint forces, timings
// Everything the log, summary and progress line say is read from the simulator's
// StepData; the runner evaluates nothing itself. The time step is the model's
// (params.solver.time_step).
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "knit/solver/simulator.hpp"

namespace knit {

struct RunOptions {
  double duration = 1.0;   ///< s of simulated time to add
  int output_every = 100;  ///< steps between written states (and log rows)
  std::string out_dir;     ///< created if missing; empty: write nothing
  bool progress = true;    ///< progress line on stderr for runs over ~2 s
  bool write_frames = true;
  /// Optional early stop, checked at every output step: return true to end the run (ok).
  std::function<bool(const StepData&, const State&)> stop_when;
  /// Optional observer, called with every written state (the initial one included),
  /// before stop_when: measurements taken along the run (stretch curves, …).
  std::function<void(const StepData&, const State&)> on_output;
  nlohmann::json extra = nlohmann::json::object();  ///< merged into summary.json
  /// Optional: called with the final state and the summary before it is written, to add
  /// fields (shape measures, …).
  std::function<void(Simulator&, const State&, nlohmann::json&)> on_finish;
};

struct RunReport {
  StepStatus status = StepStatus::OK;
  std::string message;
  long long steps = 0;
  nlohmann::json summary;
};

/// Runs and writes the outputs. On failure `state` holds the last good state, which is
/// also written to DIR/final.kstate and DIR/last_good.kstate.
RunReport run_simulation(Simulator& sim, State& state, const RunOptions& options);

/// The log.csv header for a simulator's terms and constraint groups.
std::string log_header(const Simulator& sim);
/// The summary's `constraint_forces`: per group (length excluded) its kind, force,
/// torque, torque point and max |C| in the last step.
nlohmann::json constraint_forces_json(const StepData& data);

}  // namespace knit
