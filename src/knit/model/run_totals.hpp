#pragma once
// What a run has added up from its first state to one of its states: steps, extremes,
// sums for the means, counts, and where its step halving stands. The runner keeps one as
// it steps and writes it into every state it saves (frames, checkpoints, final.kstate:
// the state file's run block), and a run resumed in its own directory starts from the one
// in the state it resumes, so that its summary covers the whole run however often it was
// stopped, not its last leg. The summary is computed from these alone (runner.cpp).
//
// Only what the run computes is here, so that two runs of the same command write the same
// state files byte for byte: the wall-clock figures (wall time, stage seconds, checkpoints)
// of the earlier legs are taken from the summary they left in the directory.
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace knit {

/// Where a HalvingStepper stands (step_halving.hpp): its counts over the run and the
/// halving the next step starts with, so that a resumed run goes on at the same step.
struct HalvingCounts {
  long long retried = 0;   ///< substeps thrown away and taken again in halves
  long long substeps = 0;  ///< substeps taken (the steps when none was halved)
  int deepest = 0;         ///< the most halvings any step needed
  int level = 0;           ///< the halvings the next step starts with
  int calm = 0;            ///< steps of h passed at `level` without a failure
};

/// What the crossing check (contact/crossings.hpp) found over a run that asked for it.
struct CrossingTotals {
  long long steps_checked = 0;
  long long count = 0;  ///< pairs of segments that passed through each other, over the steps
  /// the first one: when (s; +infinity, null in JSON, before any), its segments and where
  double first_time = std::numeric_limits<double>::infinity();
  int first_segment_a = -1, first_segment_b = -1;
  double first_x = 0, first_y = 0, first_z = 0;  ///< cm
};

struct RunTotals {
  double start_time = 0;  ///< s: the time of the run's first state
  /// s: the time the run is to end at. A resumed run asked to end there to within a
  /// millionth of a step ends exactly there (a command gives the time left in decimal).
  double end_time = 0;
  long long steps = 0;  ///< steps taken (of h, or shortened to end at the time asked)
  std::vector<double> shortened_steps;  ///< s: the steps that were not of h
  long long frames_written = 0;
  // yarn–yarn contact, over the steps that evaluated it
  long long contact_steps = 0;
  double contact_pairs_sum = 0;  ///< point pairs in contact, summed over those steps
  /// the closest approach (distance / 2r); +infinity (null in JSON) before any contact
  double min_contact_distance = std::numeric_limits<double>::infinity();
  long long contact_linearised = 0;  ///< steps whose contact was linearised (contact reuse)
  long long matrix_kept = 0;         ///< steps that kept the factor of M + h² K
  double reuse_scale_sum = 0;        ///< the reuse distance's scale, summed over the steps
  // the implicit stage's conjugate-gradient solves
  long long solve_steps = 0, solve_iterations = 0;
  int solve_iterations_max = 0;
  double solve_residual_max = 0;
  // yarn friction, over the steps that had it: pairs and stuck pairs, sweeps
  long long friction_steps = 0, friction_pairs = 0, friction_stuck = 0, friction_passes = 0;
  int friction_passes_max = 0;
  double friction_work = 0;  ///< erg dissipated
  HalvingCounts halving;
  std::map<std::string, long long> warnings;  ///< steps with each warning
  struct Object {
    double deepest_penetration = 0;  ///< cm
    double contact_points_sum = 0;   ///< its points in contact, summed over the steps
  };
  std::map<std::string, Object> objects;  ///< by object name
  /// (absent from the run blocks of states written before runs could check crossings)
  CrossingTotals crossings;
};

/// The run block of a state file: every field of `t` by name.
nlohmann::json to_json(const RunTotals& t);
/// Back from to_json's object; throws std::invalid_argument naming the field (missing, or
/// of the wrong type or range).
RunTotals run_totals_from_json(const nlohmann::json& j);

}  // namespace knit
