#pragma once
// Runs a simulation for a duration, writing states, a CSV log and a JSON summary into an
// output directory:
//   DIR/frames/state_NNNNNN.kstate   every `output_every` steps (and the initial state)
//   DIR/final.kstate                 the last state (the last good one if the run failed)
//   DIR/log.csv                      time_s, kinetic_energy, potential_energy,
//                                    max_violation, contact_pairs, min_contact_distance,
//                                    wall_s_per_step — one row per written state,
//                                    appended as the run goes
//   DIR/summary.json                 status, counts, energies, timings (see docs/)
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "knit/solver/simulator.hpp"

namespace knit {

struct RunOptions {
  double time_step = 1.0 / 11800;  ///< s
  double duration = 1.0;           ///< s of simulated time to add
  int output_every = 100;          ///< steps between written states
  std::string out_dir;             ///< created if missing
  bool progress = true;            ///< progress line on stderr for runs over ~2 s
  bool write_frames = true;
  /// Optional early stop, checked at every output step: return true to end the run (ok).
  std::function<bool(Simulator&, const State&)> stop_when;
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

/// Contact counters of a simulator's contact term, if it has one.
struct ContactReport {
  bool present = false;
  long long pairs_in_contact = 0;
  double min_distance_ratio = 0;
};
ContactReport contact_report(const Simulator& sim);

}  // namespace knit
