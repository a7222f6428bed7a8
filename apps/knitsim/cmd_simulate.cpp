// knitsim simulate SCENE.json --out DIR [--resume STATE]: a thin adapter over the
// simulate_scene recipe.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "common.hpp"
#include "knit/io/state_file.hpp"
#include "knit/recipes/simulate_scene.hpp"
#include "knit/util/run_dir.hpp"

namespace knitsim {

void register_simulate(CLI::App& app) {
  struct Opts {
    std::string scene, out, resume, knit;
    int threads = 0;
    double duration = 0;
    bool quiet = false, overwrite = false, implicit_bending = false, check_crossings = false;
    bool refuse_crossings = false;
    std::string export_format, integrator;
    double time_step = 0, contact_solve_tolerance = 0, contact_reuse = 0;
    int output_every = 0, max_step_halvings = 0;
  };
  auto opts = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("simulate", "run a scene file (JSON) and write its states");
  add_required_path(cmd, "scene", opts->scene, "scene file (JSON, docs/scene-format.md)");
  add_out_option(cmd, opts->out, "output directory");
  add_overwrite_flag(cmd, opts->overwrite);
  add_path(cmd, "--resume", opts->resume,
           "go on from a state of an earlier run of this scene (its final.kstate or a frame) "
           "to the scene's end; into that run's directory, the run goes on there",
           "none (from the scene's start)")
      ->check(existing_file());
  add_path(cmd, "--knit", opts->knit,
           "place this relaxed knit (.kstate from `knitsim relax`) where the scene's one knit "
           "is, instead of the state the scene names",
           "none (the scene's own)")
      ->check(existing_file());
  add_threads_option(cmd, opts->threads);
  add_number(cmd, "--duration", opts->duration, "override the scene's duration", "s",
             positive(knit::MAX_DURATION), "the scene's");
  // a scene that sets no parameter has the library's simulation defaults
  const knit::SolverSettings solver = knit::Params::simulation().solver;
  add_time_step_option(cmd, opts->time_step,
                       "the scene's (" + number_text(solver.time_step) + " unless it says)");
  add_integrator_option(
      cmd, opts->integrator,
      "the scene's (" + std::string(knit::integrator_name(solver.integrator)) + " unless it says)");
  add_implicit_bending_option(cmd, opts->implicit_bending);
  add_refuse_crossings_option(cmd, opts->refuse_crossings);
  add_contact_solve_tolerance_option(cmd, opts->contact_solve_tolerance, "the scene's");
  add_contact_reuse_option(cmd, opts->contact_reuse, "the scene's");
  add_max_step_halvings_option(cmd, opts->max_step_halvings, "the scene's");
  add_integer(cmd, "--output-every", opts->output_every,
              "override the scene's steps between written states and log rows", 1, 1'000'000'000,
              "steps", "the scene's");
  add_quiet_flag(cmd, opts->quiet);
  add_check_crossings_flag(cmd, opts->check_crossings);
  add_export_option(cmd, opts->export_format);
  cmd->callback([opts, cmd]() {
    // everything is validated before anything is written
    knit::Scene scene = opts->knit.empty() ? knit::load_scene(opts->scene)
                                           : knit::load_scene_with_knit(opts->scene, opts->knit);
    if (cmd->count("--time-step")) scene.model.params.solver.time_step = opts->time_step;
    if (cmd->count("--integrator"))
      scene.model.params.solver.integrator = knit::parse_integrator(opts->integrator);
    if (opts->implicit_bending) scene.model.params.solver.implicit_bending = true;
    if (opts->refuse_crossings) scene.model.params.solver.refuse_crossings = true;
    if (cmd->count("--contact-solve-tolerance"))
      scene.model.params.solver.contact_solve_tolerance = opts->contact_solve_tolerance;
    if (cmd->count("--contact-reuse"))
      scene.model.params.solver.contact_reuse = opts->contact_reuse;
    if (cmd->count("--max-step-halvings"))
      scene.model.params.solver.max_step_halvings = opts->max_step_halvings;
    if (cmd->count("--output-every")) scene.output_every = opts->output_every;
    if (cmd->count("--duration")) {
      knit::check_duration(opts->duration, scene.model.params.solver.time_step);
      scene.duration = opts->duration;
    }
    knit::SimulateOptions run;
    if (!opts->resume.empty()) {
      const knit::StateFile f = knit::read_state_file(opts->resume);
      std::vector<int> counts;
      for (const knit::YarnInfo& y : scene.model.yarns) counts.push_back(y.num_cp());
      if (f.yarn_cp_counts != counts)
        throw std::invalid_argument(
            "--resume " + opts->resume + ": it holds " + std::to_string(f.yarn_cp_counts.size()) +
            " yarn(s) and " + std::to_string(f.num_cp()) + " control points, but " + opts->scene +
            " has " + std::to_string(counts.size()) + " and " +
            std::to_string(scene.model.num_cp()) + ": it is not a state of this scene");
      if (f.state.time >= scene.duration - 1e-6 * scene.model.params.solver.time_step)
        throw std::invalid_argument("--resume " + opts->resume +
                                    ": the state is at t = " + knit::short_number(f.state.time) +
                                    " s, already at the scene's end (" +
                                    knit::short_number(scene.duration) +
                                    " s): give a longer --duration to go on");
      scene.state = f.state;
      run.continue_in_place = knit::resumes_in_place(opts->resume, opts->out);
      run.resumed_totals = f.run;
      run.extra["resumed_from"] = opts->resume;
    }
    auto control = make_thread_control(opts->threads);
    run.out_dir = opts->out;
    run.overwrite = opts->overwrite;
    run.progress = !opts->quiet;
    run.check_crossings = opts->check_crossings;
    run.extra["scene"] = std::filesystem::absolute(opts->scene).lexically_normal().string();
    if (!opts->knit.empty())
      run.extra["knit_state"] = std::filesystem::absolute(opts->knit).lexically_normal().string();
    add_provenance(run.extra);
    run.resume_command = resume_command(opts->out);
    const knit::RunReport report = knit::simulate_scene(scene, run);
    finish_run(report, opts->out, opts->export_format, scene.model.objects);
  });
}

const bool simulate_added = add_command(10, register_simulate);

}  // namespace knitsim
