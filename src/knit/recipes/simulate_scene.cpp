#include "knit/recipes/simulate_scene.hpp"

#include "knit/filters/nonrigid_damping.hpp"
#include "knit/filters/yarn_friction.hpp"
#include "knit/objects/collision_filter.hpp"
#include "knit/objects/object.hpp"
#include "knit/util/run_dir.hpp"

namespace knit {

std::vector<std::unique_ptr<VelocityFilter>> scene_filters(const Scene& scene, const Model& model) {
  std::vector<std::unique_ptr<VelocityFilter>> filters;
  const Material& m = scene.model.params.material;
  for (const SceneKnit& k : scene.knits)
    filters.push_back(std::make_unique<NonRigidDampingFilter>(model, m.alpha_small, m.alpha_large,
                                                              k.in_the_round));
  if (std::any_of(scene.model.objects.begin(), scene.model.objects.end(),
                  [](const auto& o) { return o->filter; }))
    filters.push_back(std::make_unique<CollisionFilter>(model));
  // friction after the collisions: it reads the normal forces of the step's start
  if (m.contact && m.yarn_friction > 0)
    filters.push_back(std::make_unique<YarnFrictionFilter>(m.yarn_friction));
  return filters;
}

std::unique_ptr<Simulator> make_scene_simulator(const Scene& scene) {
  auto sim = std::make_unique<Simulator>(scene.model);
  for (auto& f : scene_filters(scene, sim->model())) sim->add_filter(std::move(f));
  return sim;
}

RunOptions scene_run_options(const Scene& scene, const SimulateOptions& o) {
  RunOptions run;
  run.duration = scene.duration;
  run.end_time = scene.duration;  // scenes start at t = 0; a resumed one goes on to the end
  run.continue_in_place = o.continue_in_place;
  run.resumed_totals = o.resumed_totals;
  run.resume_command = o.resume_command;
  run.output_every = scene.output_every;
  run.out_dir = o.out_dir;
  run.progress = o.progress;
  run.write_frames = o.write_frames;
  run.check_crossings = o.check_crossings;
  run.extra = o.extra;
  return run;
}

RunReport simulate_scene(Scene& scene, const SimulateOptions& o) {
  auto sim = make_scene_simulator(scene);
  RunOptions run = scene_run_options(scene, o);
  validate_params(scene.model.params);
  check_duration(scene.duration, scene.model.params.solver.time_step);
  check_start(*sim, scene.state);
  RunDirectory held;
  if (!o.out_dir.empty())
    held = o.continue_in_place ? continue_run_directory(o.out_dir)
                               : prepare_run_directory(o.out_dir, o.overwrite);
  if (!scene.knits.empty()) {
    nlohmann::json knits = nlohmann::json::array();
    for (const SceneKnit& k : scene.knits)
      knits.push_back({{"state", k.source}, {"yarn", k.yarn}, {"in_the_round", k.in_the_round}});
    run.extra["knits"] = knits;
  }
  return run_simulation(*sim, scene.state, run);
}

}  // namespace knit
