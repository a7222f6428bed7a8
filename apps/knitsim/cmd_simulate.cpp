// knitsim simulate SCENE.json --out DIR: a thin adapter over the simulate_scene recipe.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "common.hpp"
#include "knit/recipes/simulate_scene.hpp"

namespace knitsim {

void register_simulate(CLI::App& app) {
  struct Opts {
    std::string scene, out;
    int threads = 0;
    double duration = -1;
    bool quiet = false, overwrite = false;
    std::string export_format;
  };
  auto opts = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("simulate", "run a scene file (JSON) and write its states");
  cmd->add_option("scene", opts->scene, "scene file (JSON)")->required();
  cmd->add_option("--out,-o", opts->out, "output directory")->required();
  cmd->add_flag("--overwrite", opts->overwrite,
                "replace the files of an earlier run in the output directory");
  add_threads_option(cmd, opts->threads);
  cmd->add_option("--duration", opts->duration, "override the scene's duration (s)");
  cmd->add_flag("--quiet,-q", opts->quiet, "no progress line");
  add_export_option(cmd, opts->export_format);
  cmd->callback([opts]() {
    // everything is validated before anything is written
    knit::Scene scene = knit::load_scene(opts->scene);
    if (opts->duration >= 0) scene.duration = opts->duration;
    auto control = make_thread_control(opts->threads);
    knit::SimulateOptions run;
    run.out_dir = opts->out;
    run.overwrite = opts->overwrite;
    run.progress = !opts->quiet;
    run.extra["scene"] = opts->scene;
    const knit::RunReport report = knit::simulate_scene(scene, run);
    print_report(report, opts->out);
    export_run(opts->out, opts->export_format);
    if (report.status != knit::StepStatus::OK) throw RunFailed();
  });
}

}  // namespace knitsim
