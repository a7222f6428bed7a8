#include "knit/solver/relaxation.hpp"

namespace knit {

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
  run.stop_when = [&](const StepData& data, const State&) {
    reached = data.kinetic_energy / length < o.ke_per_length;
    return reached;
  };
  extra["ke_per_length_threshold"] = o.ke_per_length;
  run.extra = extra;
  run.on_finish = [&](Simulator& s, const State& st, nlohmann::json& summary) {
    summary["relaxed"] = reached;
    summary["ke_per_length"] = s.data().kinetic_energy / length;
    if (on_finish) on_finish(s, st, summary);
  };
  return run_simulation(sim, state, run);
}

}  // namespace knit
