#include "knit/solver/relaxation.hpp"

#include <cmath>
#include <stdexcept>

namespace knit {

void validate_relax_options(const RelaxOptions& o, double time_step) {
  try {
    check_duration(o.max_time, time_step);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("max-time: ") + e.what());
  }
  if (!std::isfinite(o.ke_per_length) || !(o.ke_per_length > 0))
    throw std::invalid_argument("ke-threshold = " + short_number(o.ke_per_length) +
                                " erg/cm: expected a finite number > 0");
  if (!std::isfinite(o.force_residual) || o.force_residual < 0)
    throw std::invalid_argument("residual = " + short_number(o.force_residual) +
                                " cm/s²: expected a finite number ≥ 0 (0: the kinetic-energy "
                                "test)");
  if (o.check_every < 1)
    throw std::invalid_argument("check-every = " + std::to_string(o.check_every) +
                                ": expected at least 1 step");
}

RunReport relax(Simulator& sim, State& state, const RelaxOptions& o, nlohmann::json extra,
                std::function<void(Simulator&, const State&, nlohmann::json&)> on_finish) {
  const double length = sim.model().total_length();
  bool reached = false;
  RunOptions run;
  run.duration = o.max_time;
  run.output_every = o.check_every;
  run.out_dir = o.out_dir;
  run.progress = o.progress;
  run.write_frames = o.write_frames;
  run.continue_in_place = o.continue_in_place;
  run.resume_command = o.resume_command;
  run.halving_calm_steps = o.halving_calm_steps;
  const bool residual_test = o.force_residual > 0;
  // every check measures the force residual (a force evaluation and two projections per
  // check_every steps), so that the log shows how far from rest a run is by both tests
  run.before_output = [](Simulator& s, const State& st) { s.force_residual(st); };
  run.stop_when = [&](const StepData& data, const State&) {
    reached = residual_test ? data.force_residual < o.force_residual
                            : data.kinetic_energy / length < o.ke_per_length;
    return reached;
  };
  extra["rest_test"] = residual_test ? "residual" : "kinetic_energy";
  extra["ke_per_length_threshold"] = o.ke_per_length;
  if (residual_test) extra["force_residual_threshold"] = o.force_residual;
  run.extra = extra;
  run.on_finish = [&](Simulator& s, const State& st, nlohmann::json& summary) {
    summary["relaxed"] = reached;
    summary["ke_per_length"] = s.data().kinetic_energy / length;
    if (on_finish) on_finish(s, st, summary);
  };
  return run_simulation(sim, state, run);
}

}  // namespace knit
