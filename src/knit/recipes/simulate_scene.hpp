#pragma once
// Recipe: "simulate a scene". The scene's model with the default terms (gravity, bending,
// length, global damping when k_global > 0, yarn–yarn contact), and for a placed knit the
// non-rigid damping filter built from its stitch coordinates (α_small, α_large of the
// scene's material), then the collision filter for the objects that use it (the penalty
// term is one of the default terms), run for the scene's duration with its time step.
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "knit/run/runner.hpp"
#include "knit/scene/scene.hpp"

namespace knit {

/// The simulator for a scene (see above), ready to step scene.state.
std::unique_ptr<Simulator> make_scene_simulator(const Scene& scene);
/// The velocity filters make_scene_simulator adds, in order, for a simulator whose model
/// is `model` (the simulator's own copy of scene.model: the filters keep a reference).
std::vector<std::unique_ptr<VelocityFilter>> scene_filters(const Scene& scene, const Model& model);

struct SimulateOptions {
  std::string out_dir;     ///< empty: write nothing
  bool overwrite = false;  ///< empty a directory that holds another run's files first
  bool progress = true;    ///< progress line on stderr
  bool write_frames = true;
  bool check_crossings = false;  ///< RunOptions::check_crossings
  /// The scene's state was resumed from a state of the run in out_dir: go on there (see
  /// RunOptions::continue_in_place) instead of requiring an empty directory.
  bool continue_in_place = false;
  /// The totals of the state resumed (RunOptions::resumed_totals).
  std::optional<RunTotals> resumed_totals;
  std::string resume_command;  ///< written into the summary of an interrupted run
  nlohmann::json extra = nlohmann::json::object();  ///< merged into the summary
};

/// The run options for a scene: its duration and output interval, and the options' output
/// directory, progress line, frames and summary fields.
RunOptions scene_run_options(const Scene& scene, const SimulateOptions& options);

/// Runs `scene` from scene.state (which ends as the last state) until t = scene.duration
/// (a resumed state goes on to the same end).
RunReport simulate_scene(Scene& scene, const SimulateOptions& options);

}  // namespace knit
