#pragma once
// Runs a simulation for a duration, writing states, a CSV log and a JSON summary into an
// output directory (or nothing at all when no directory is given):
//   DIR/frames/state_NNNNNN.kstate   every `output_every` steps (and the initial state)
//   DIR/final.kstate                 the last state (the last good one if the run failed)
//   DIR/log.csv                      time_s, kinetic_energy, potential_energy,
//                                    max_violation, contact_pairs, min_contact_distance,
//                                    wall_s_per_step, force_residual,
//                                    energy_<term>…, <group>_fx/fy/fz…
//                                    — one row per written state, appended as the run goes
//   DIR/summary.json                 status, counts, energies, constraint forces, timings
// Everything the log, summary and progress line say is read from the simulator's
// StepData; the runner evaluates nothing itself. The time step is the model's
// (params.solver.time_step).
//
// A run stopped (interrupted, killed after a checkpoint, or failed) and resumed in its
// own directory is one run: every state the runner writes carries what the run has added
// up so far (RunTotals, the state file's run block), a resumed run starts from the totals
// of its state, and the summary is computed from the totals alone. So the summary of a
// run resumed any number of times is the uninterrupted run's (its steps, extremes, means
// and counts), but for the wall-clock figures (wall_time_s, stage_seconds,
// checkpoints_written and what is computed from them), which are sums over the legs (the
// earlier legs' read from the summary they left), and the leg's own provenance
// (resumed_from, the command line); and its log.csv has the uninterrupted run's rows (an
// interrupt writes none between two output steps).
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "knit/model/run_totals.hpp"
#include "knit/solver/simulator.hpp"

namespace knit {

struct RunOptions {
  double duration = 1.0;  ///< s of simulated time to add (unless end_time is set)
  /// When set (finite): run until the state's time reaches this (s), whatever it starts
  /// at — a resumed run then takes exactly the steps the uninterrupted one would have.
  double end_time = std::numeric_limits<double>::quiet_NaN();
  int output_every = 100;  ///< steps between written states (and log rows)
  std::string out_dir;     ///< created if missing; empty: write nothing
  /// Go on with the run already in out_dir (resumed from one of its states): log.csv is
  /// appended to (its rows after the start time dropped), frames keep their numbering.
  bool continue_in_place = false;
  /// With continue_in_place: the totals of the state the run resumes from (StateFile::
  /// run), from which the run's totals go on. Absent (a state written before states
  /// carried them), the summary covers the run from the resumed state on and says so
  /// ("totals_since_s"). Ignored without continue_in_place: a run from another
  /// directory's state is a run of its own.
  std::optional<RunTotals> resumed_totals;
  /// The command that resumes this run from DIR/final.kstate, written into the summary
  /// of an interrupted or failed run ("" : none).
  std::string resume_command;
  bool progress = true;  ///< progress line on stderr for runs over ~2 s
  bool write_frames = true;
  /// Without frames, a run that writes keeps a state on disk no more than this many wall
  /// seconds old: at the first output step after that, DIR/final.kstate is written
  /// (atomically, the state as it is: the run's results do not change) and summary.json
  /// says "status": "running" with the command that resumes from it, so that a run killed
  /// outright (SIGKILL, the machine gone) goes on from there. 0: never.
  double checkpoint_every_s = 600;
  /// With SolverSettings::max_step_halvings: steps that pass at a halved step before it
  /// doubles again (HalvingStepper); 0 (the default) keeps the halved step to the end.
  int halving_calm_steps = 0;
  /// Check every step for yarns that passed through each other (contact/crossings.hpp,
  /// between the state before the step and after it): the summary's `crossings` says how
  /// many steps were checked, how many pairs of segments crossed (0 expected) and the
  /// first (time, segments, yarns, point). Costs about as much as a contact evaluation.
  bool check_crossings = false;
  /// Optional measurement at every output step, before the log row and the state are
  /// written, that StepData should carry into them (relaxations: the force residual).
  std::function<void(Simulator&, const State&)> before_output;
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
  long long steps = 0;  ///< of the run (a resumed run's earlier legs included)
  nlohmann::json summary;
};

/// Runs and writes the outputs. On failure `state` holds the last good state, which is
/// also written to DIR/final.kstate and DIR/last_good.kstate. The options and the model's
/// parameters are checked first (std::invalid_argument naming the bad one, nothing
/// written). Steps are the model's time step h; when the duration is not a multiple of h
/// the last one or two steps are shortened (never below h/2) so the run ends at exactly
/// the time asked, and the summary says so. While an InterruptHandler is installed
/// (interrupt.hpp), a SIGINT/SIGTERM ends the run after the current step with status
/// INTERRUPTED: the state is in DIR/final.kstate and the summary holds the command to
/// resume. An interrupt between two output steps writes no log row or frame (the state is
/// in final.kstate) and does not ask stop_when, so that the resumed run goes on as the
/// uninterrupted one. A signal that comes during the run's last step leaves it finished
/// (status OK): nothing would be left to resume.
RunReport run_simulation(Simulator& sim, State& state, const RunOptions& options);

/// Evaluates the forces at `state` and throws std::invalid_argument when yarns start
/// inside each other (closer than 5 % of a yarn diameter), naming the yarns and segments,
/// or when a yarn's centreline starts inside a solid object, naming the object.
/// run_simulation calls it; recipes call it before they write anything.
void check_start(Simulator& sim, const State& state);

/// The step lengths a run takes from `time` to `end_time` with time step h: h while more
/// than 1.5 h remains, then the rest in one step (≤ h) or two equal ones (≤ 0.75 h). What
/// is left within 1e-6 h of h is one step of exactly h, and within 1e-6 h of 0 nothing
/// (the rounding of a time summed over many steps). Returns the next step, or 0 at the end.
double next_step_length(double time, double end_time, double h);

/// Every parameter of a model as JSON (material, discretisation, solver, gravity), for
/// the summary's provenance.
nlohmann::json params_json(const Params& params);

/// The version of knitsim (e.g. "0.4.0"), recorded in every summary.
const char* knitsim_version();

/// The log.csv header for a simulator's terms and constraint groups.
std::string log_header(const Simulator& sim);
/// The summary's `constraint_forces`: per group (length excluded) its kind, force,
/// torque, torque point and max |C| in the last step.
nlohmann::json constraint_forces_json(const StepData& data);

}  // namespace knit
