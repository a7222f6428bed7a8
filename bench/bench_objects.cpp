// The cost of solid objects in a step: the same scene and state stepped with its objects
// (penalty term and collision filter) and without them, alternating in one sitting so the
// two are measured under the same machine load. Default: examples/drape_sphere.json from a
// state of its run where the swatch lies on the ball.
//   bench_objects [--scene S] [--knit K.kstate] [--state FRAME.kstate] [--steps N]
//                 [--rounds N] [--threads N]
#include <CLI/CLI.hpp>
#include <iostream>

#include "bench_util.hpp"
#include "knit/io/state_file.hpp"
#include "knit/recipes/simulate_scene.hpp"

int main(int argc, char** argv) {
  std::string scene_path = std::string(KNIT_EXAMPLES) + "/drape_sphere.json", knit_state, state;
  int steps = 100, rounds = 3, threads = 0;
  CLI::App app{"bench_objects: step cost with and without a scene's objects"};
  app.add_option("--scene", scene_path, "scene file with objects");
  app.add_option("--knit", knit_state, "place this relaxed knit instead of the scene's");
  app.add_option("--state", state,
                 "start from this state of a run of the scene (e.g. a frame where the knit "
                 "touches the objects; default: the scene's start)");
  app.add_option("--steps", steps, "steps per timing");
  app.add_option("--rounds", rounds, "alternating rounds with and without the objects");
  app.add_option("--threads", threads, "0 = all cores");
  CLI11_PARSE(app, argc, argv);
  const auto cap = knit::bench::limit_threads(threads);
  knit::Scene scene = knit_state.empty() ? knit::load_scene(scene_path)
                                         : knit::load_scene_with_knit(scene_path, knit_state);
  if (!state.empty()) scene.state = knit::read_state_file(state).state;
  knit::Scene bare = scene;
  bare.model.objects.clear();
  auto with = knit::make_scene_simulator(scene), without = knit::make_scene_simulator(bare);
  const double h = scene.model.params.solver.time_step;
  knit::State s_with = scene.state, s_without = scene.state;
  auto run = [&](knit::Simulator& sim, knit::State& s) {
    sim.reset_timings();
    const double t0 = knit::bench::now_s();
    for (int i = 0; i < steps; ++i)
      if (!sim.step(s, h).ok()) throw std::runtime_error("a step failed");
    return (knit::bench::now_s() - t0) / steps;
  };
  run(*with, s_with);  // warm up both
  run(*without, s_without);
  std::vector<double> t_with, t_without;
  nlohmann::json stages = nlohmann::json::object();
  for (int r = 0; r < rounds; ++r) {
    // each round from the same state, so both see the same contacts
    s_with = scene.state;
    s_without = scene.state;
    t_with.push_back(run(*with, s_with));
    t_without.push_back(run(*without, s_without));
  }
  for (const auto& [name, sec] : with->data().stage_seconds)
    stages[name + "_ms_per_step"] = 1e3 * sec / steps;
  const double a = knit::bench::median(t_with), b = knit::bench::median(t_without);
  long long points = 0;
  for (const knit::ObjectRecord& o : with->data().objects) points += o.points_in_contact;
  nlohmann::json out = {{"benchmark", "objects"},
                        {"scene", scene_path},
                        {"segments", scene.model.num_seg()},
                        {"objects", scene.model.objects.size()},
                        {"object_contact_points_at_end", points},
                        {"threads", knit::bench::active_threads()},
                        {"steps", steps},
                        {"rounds", rounds},
                        {"ms_per_step_with_objects", 1e3 * a},
                        {"ms_per_step_without", 1e3 * b},
                        {"slowdown", a / b - 1},
                        {"stages_with_objects", stages},
                        {"machine", knit::bench::machine_info()}};
  std::cout << out.dump(2) << "\n";
}
