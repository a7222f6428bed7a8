#include "knit/run/relaxation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace knit {

void validate_relax_options(const RelaxOptions& o, const SolverSettings& solver) {
  try {
    check_duration(o.max_time, solver.time_step);
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
  if (!std::isfinite(o.contact_reuse_widen) || !(o.contact_reuse_widen >= 1))
    throw std::invalid_argument("contact-reuse-widen = " + short_number(o.contact_reuse_widen) +
                                ": expected a finite factor ≥ 1 (1: no widening)");
  if (!std::isfinite(o.contact_reuse_widen_residual) || !(o.contact_reuse_widen_residual > 0))
    throw std::invalid_argument(
        "contact-reuse-widen-residual = " + short_number(o.contact_reuse_widen_residual) +
        " cm/s²: expected a finite number > 0");
  if (o.contact_reuse_widen > 1 && !(solver.contact_reuse > 0))
    throw std::invalid_argument("contact-reuse-widen = " + short_number(o.contact_reuse_widen) +
                                " widens contact reuse, which is off (give --contact-reuse "
                                "with the imex-contact integrator)");
  if (o.check_every < 1)
    throw std::invalid_argument("check-every = " + std::to_string(o.check_every) +
                                ": expected at least 1 step");
}

RunReport relax(Simulator& sim, State& state, const RelaxOptions& o, nlohmann::json extra,
                std::function<void(Simulator&, const State&, nlohmann::json&)> on_finish) {
  const double length = sim.model().total_length();
  validate_relax_options(o, sim.model().params.solver);
  const bool widen = o.contact_reuse_widen > 1;
  bool reached = false;
  RunOptions run;
  run.duration = o.max_time;
  run.output_every = o.check_every;
  run.out_dir = o.out_dir;
  run.progress = o.progress;
  run.write_frames = o.write_frames;
  run.checkpoint_every_s = o.checkpoint_every_s;
  run.continue_in_place = o.continue_in_place;
  run.resumed_totals = o.resumed_totals;
  run.resume_command = o.resume_command;
  run.halving_calm_steps = o.halving_calm_steps;
  run.check_crossings = o.check_crossings;
  const bool residual_test = o.force_residual > 0;
  // every check measures the force residual (a force evaluation and two projections per
  // check_every steps), so that the log shows how far from rest a run is by both tests
  // (and sets the reuse distances' scale for the steps until the next check; the
  // simulator's own scale is restored on return)
  struct ScaleGuard {
    Simulator& sim;
    double scale;
    ~ScaleGuard() { sim.set_reuse_scale(scale); }
  } guard{sim, sim.reuse_scale()};
  auto check = [&](Simulator& s, const State& st) {
    const double r = s.force_residual(st);
    if (widen && std::isfinite(r))
      s.set_reuse_scale(std::clamp(r / o.contact_reuse_widen_residual, 1.0, o.contact_reuse_widen));
  };
  run.before_output = check;
  // a run that goes on in place writes no output at its start: its first steps are widened
  // by the state it starts from all the same
  if (widen && o.continue_in_place) check(sim, state);
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
    if (widen)
      summary["contact_reuse_widen"] = {{"max", o.contact_reuse_widen},
                                        {"residual", o.contact_reuse_widen_residual}};
    if (on_finish) on_finish(s, st, summary);
  };
  return run_simulation(sim, state, run);
}

}  // namespace knit
