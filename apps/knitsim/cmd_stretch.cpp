// knitsim stretch PATTERN --direction course|wale|bias --to STRAIN --out DIR
// knitsim stretch --from relaxed.kstate --direction … --out DIR
// knitsim stretch --from relaxed.kstate --sheet [--fit RUN,RUN,RUN] --direction … --out DIR
// knitsim stretch … --out DIR --resume DIR|STATE   (go on with a stopped run)
// knitsim stretch DIR1 DIR2 … --plot curves.png
// A thin adapter over the stretch recipe (src/knit/recipes/stretch.hpp); a PATTERN is
// first relaxed with the relax recipe's defaults.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "common.hpp"
#include "knit/io/state_file.hpp"
#include "knit/present/plot.hpp"
#include "knit/present/stretch_figures.hpp"
#include "knit/recipes/relax_knit.hpp"
#include "knit/recipes/sheet_stretch.hpp"
#include "knit/recipes/stretch.hpp"
#include "knit/util/run_dir.hpp"

namespace knitsim {

namespace {
// seconds of relaxation before a PATTERN is pulled (this command's own default)
constexpr double STRETCH_RELAX_TIME = 1.0;
}  // namespace

void register_stretch(CLI::App& app) {
  struct Opts {
    knit::StretchOptions stretch;
    knit::SheetStretchOptions sheet;
    knit::RelaxKnitOptions relax;
    std::vector<std::string> inputs;
    std::string from, out, plot, resume;
    // the pull's and the solver's options start at the recipe's own values
    std::string direction = knit::stretch_direction_name(stretch.direction);
    std::string integrator = knit::integrator_name(stretch.params.solver.integrator);
    bool use_sheet = false;
    std::vector<std::string> fit;
    double relax_time = STRETCH_RELAX_TIME;
    int threads = 0;
    bool quiet = false, no_frames = false, no_render = false, overwrite = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "stretch", "pull a relaxed knit between two clamps and record its force–strain curve");
  cmd->add_option("inputs", o->inputs)
      ->type_name("PATH")
      ->description(
          "a PATTERN to knit, relax and stretch (built-in or chart file); or, with "
          "--plot, stretch runs' directories to draw together\n" +
          value_line("name or paths", "none: give a PATTERN or --from"));
  add_path(cmd, "--from", o->from, "stretch this relaxed knit (.kstate from `knitsim relax`)",
           "none (a PATTERN, relaxed first)")
      ->check(existing_file());
  add_out_option(cmd, o->out, "output directory", "none (required, except with --plot)");
  add_overwrite_flag(cmd, o->overwrite);
  add_path(cmd, "--resume", o->resume,
           "go on with the stopped run in --out: from its final.kstate, one of its frames, or "
           "the directory itself (its latest state with a sample in stretch.csv); the same "
           "command otherwise",
           "none (a new run)");
  add_path(cmd, "--plot", o->plot, "draw the force–strain curves of the given run directories",
           "none (run a pull)", "path (PNG)");
  add_choice(cmd, "--direction,-d", o->direction, "the pull's direction in the fabric",
             {"course", "wale", "bias"});
  add_number(cmd, "--to", o->stretch.to_strain, "nominal strain to pull to (1 = doubled length)",
             "strain", positive(10));
  add_integer(cmd, "--cycles", o->stretch.cycles, "further half-cycles: back, out, …", 0, 100,
              "count");
  add_number(cmd, "--speed", o->stretch.speed, "speed of the moving clamp", "cm/s", positive(1000));
  add_number(cmd, "--hold", o->stretch.hold_strain,
             "pull in steps of this much strain, holding the clamps still after each (and at "
             "strain 0 first) while FIRE relaxes the yarn toward rest; the curve is the clamps' "
             "static reactions at the ends of the holds",
             "strain", closed(0, 10), number_text(o->stretch.hold_strain) + " (a continuous pull)");
  add_number(cmd, "--hold-time", o->stretch.hold_time,
             "with --hold: simulated time each hold lasts", "s", positive(100));
  cmd->add_flag("--hold-damped", o->stretch.hold_damped,
                "with --hold: hold with the simulation's damping instead of FIRE (a "
                "stress-relaxation test)");
  add_number(cmd, "--max-force", o->stretch.max_force,
             "end the pull at the first sample (every 0.01 strain) where either clamp's force "
             "along it exceeds this, as a tensile tester's load limit; the summary's "
             "stretch.stopped says where",
             "dyn", closed(0, 1e12), number_text(o->stretch.max_force) + " (no limit)");
  add_integer(cmd, "--clamp-stitches", o->stretch.clamp_stitches,
              "columns, rows or corner stitches held by each clamp", 1, 1'000'000, "count");
  knit::SolverSettings& solver = o->stretch.params.solver;
  add_time_step_option(cmd, solver.time_step);
  add_integrator_option(cmd, o->integrator);
  add_implicit_bending_option(cmd, solver.implicit_bending);
  add_refuse_crossings_option(cmd, solver.refuse_crossings);
  add_contact_solve_tolerance_option(cmd, solver.contact_solve_tolerance);
  add_contact_reuse_option(cmd, solver.contact_reuse);
  add_max_step_halvings_option(cmd, solver.max_step_halvings);
  add_end_mass_floor_option(cmd, o->stretch.params.discretisation.end_mass_floor);
  add_contact_points_option(cmd, o->stretch.params.discretisation.contact_points);
  cmd->add_flag("--sheet", o->use_sheet,
                "stretch the elastic-sheet model (Baraff–Witkin) carrying the knit's geometry, "
                "quasi-statically, instead of the yarn model");
  cmd->add_option("--fit", o->fit)
      ->delimiter(',')
      ->type_name("PATH")
      ->description(
          "with --sheet: fit the sheet's stiffnesses to these yarn stretch runs of "
          "the same knit (course, wale, bias; comma-separated directories)\n" +
          value_line("paths", "none (the stiffnesses given)"));
  knit::sheet::SheetMaterial& sheet = o->sheet.material;
  add_number(cmd, "--k-course", sheet.k_stretch_u,
             "with --sheet: stretch stiffness along the course", "dyn/cm", positive(1e12));
  add_number(cmd, "--k-wale", sheet.k_stretch_v, "with --sheet: stretch stiffness along the wale",
             "dyn/cm", positive(1e12));
  add_number(cmd, "--k-shear", sheet.k_shear, "with --sheet: shear stiffness", "dyn/cm",
             positive(1e12));
  add_number(cmd, "--k-bend", sheet.k_bend, "with --sheet: bending stiffness per hinge", "erg",
             closed(0, 1e12));
  add_number(cmd, "--node-spacing", o->sheet.node_spacing,
             "with --sheet: distance between the sheet's grid nodes", "cm", closed(0.05, 10));
  add_damping_options(cmd, o->stretch.params.material);
  add_number(cmd, "--yarn-friction", o->stretch.params.material.yarn_friction,
             "yarn–yarn Coulomb friction coefficient μ (0: the paper's model, viscous contact "
             "damping only)",
             "dimensionless", param("yarn_friction"));
  add_size_options(cmd, o->relax.knit.rows, o->relax.knit.cols, "rows of the PATTERN's sample",
                   "stitches per row of the PATTERN's sample");
  cmd->add_flag("--bind-off", o->relax.knit.bind_off,
                "bind off the PATTERN's last row before relaxing it (see `knitsim relax`)");
  cmd->add_flag("--cast-on", o->relax.knit.cast_on,
                "cast on the PATTERN's first row before relaxing it (see `knitsim relax`)");
  add_number(cmd, "--relax-time", o->relax_time, "relaxation of a PATTERN before the pull", "s",
             positive(knit::MAX_DURATION));
  add_threads_option(cmd, o->threads);
  cmd->add_flag("--no-frames", o->no_frames, "write no states along the way (and no renders)");
  cmd->add_flag("--no-render", o->no_render,
                "no renders at strains 0, 0.25, 0.5, 1 and no movie of the frames");
  add_quiet_flag(cmd, o->quiet);
  add_check_crossings_flag(cmd, o->stretch.check_crossings);
  cmd->callback([o, cmd]() {
    if (!o->plot.empty()) {
      if (o->inputs.empty())
        throw std::invalid_argument("stretch --plot: give the stretch runs' directories");
      knit::check_plot_path(o->plot, "--plot");
      const std::string written = knit::plot_stretch_runs(o->inputs, o->plot);
      std::cout << "wrote " << written << "\n";
      return;
    }
    if (o->out.empty()) throw std::invalid_argument("stretch: --out is required");
    if (!o->use_sheet &&
        (!o->fit.empty() || cmd->count("--k-course") + cmd->count("--k-wale") +
                                    cmd->count("--k-shear") + cmd->count("--k-bend") +
                                    cmd->count("--node-spacing") >
                                0))
      throw std::invalid_argument("stretch: --fit, --k-* and --node-spacing need --sheet");
    if (o->from.empty() == (o->inputs.size() != 1))
      throw std::invalid_argument("stretch: give either one PATTERN or --from STATE");
    if (o->relax.knit.bind_off && !o->from.empty())
      throw std::invalid_argument(
          "stretch --bind-off: binds off a PATTERN before relaxing it; a state --from keeps "
          "what it was knitted with (`knitsim relax --bind-off` makes one)");
    if (o->relax.knit.cast_on && !o->from.empty())
      throw std::invalid_argument(
          "stretch --cast-on: casts on a PATTERN before relaxing it; a state --from keeps "
          "what it was knitted with (`knitsim relax --cast-on` makes one)");
    if (!o->resume.empty()) {
      if (o->use_sheet)
        throw std::invalid_argument(
            "stretch --resume: the sheet's runs take seconds; run them again instead");
      if (o->from.empty()) {
        // a PATTERN's run keeps the relaxed knit it pulled beside its curve
        o->from = (std::filesystem::path(o->out) / "relaxed.kstate").string();
        if (!std::filesystem::exists(o->from))
          throw std::invalid_argument("stretch --resume: " + o->from +
                                      ", the relaxed knit the run pulled, is missing: give it "
                                      "with --from");
        o->inputs.clear();
      }
    }
    o->stretch.direction = knit::parse_stretch_direction(o->direction);
    o->stretch.params.solver.integrator = knit::parse_integrator(o->integrator);
    if (o->use_sheet &&
        (cmd->count("--hold") + cmd->count("--hold-time") + cmd->count("--hold-damped") +
             cmd->count("--time-step") + cmd->count("--integrator") +
             cmd->count("--implicit-bending") + cmd->count("--contact-solve-tolerance") +
             cmd->count("--contact-reuse") + cmd->count("--yarn-friction") +
             cmd->count("--end-mass-floor") + cmd->count("--max-step-halvings") +
             cmd->count("--refuse-crossings") + cmd->count("--max-force") >
         0))
      throw std::invalid_argument(
          "stretch --sheet: the sheet is pulled through equilibria already; --hold, "
          "--hold-time, --hold-damped, --time-step, --integrator, --implicit-bending, "
          "--contact-solve-tolerance, --contact-reuse, --yarn-friction, --end-mass-floor, "
          "--max-step-halvings, --refuse-crossings and --max-force are for the yarn model");
    if ((cmd->count("--hold-time") || o->stretch.hold_damped) && !cmd->count("--hold"))
      throw std::invalid_argument("stretch: --hold-time and --hold-damped need --hold");
    o->stretch.out_dir = o->out;
    o->stretch.overwrite = o->overwrite;
    o->stretch.progress = !o->quiet;
    o->stretch.write_frames = !o->no_frames;
    o->stretch.render = !o->no_render;
    o->stretch.figures = knit::write_stretch_figures;  // the plots, renders and movie
    o->stretch.resume = o->resume;
    o->stretch.resume_command = resume_command(o->out);
    add_provenance(o->stretch.extra);
    // before a relaxation of minutes (a resumed run goes on in its own directory)
    if (o->resume.empty()) knit::check_run_directory(o->out, o->overwrite);
    auto control = make_thread_control(o->threads);
    std::string from = o->from;
    std::string temp;
    if (from.empty()) {
      // knit and relax the pattern in memory; its relaxed state goes beside the stretch run
      o->relax.run.max_time = o->relax_time;
      o->relax.run.progress = !o->quiet;
      o->relax.run.check_crossings = o->stretch.check_crossings;
      if (!o->quiet) std::cerr << "relaxing " << o->inputs[0] << " first\n";
      const knit::RelaxResult r = knit::relax_knit(o->inputs[0], o->relax);
      char name[] = "/tmp/knitsim-stretch-XXXXXX";
      const int fd = mkstemp(name);
      if (fd < 0) throw std::runtime_error("stretch: cannot create a temporary file");
      close(fd);
      temp = name;
      knit::write_state_file(temp, knit::make_state_file(r.model, r.state));
      from = temp;
    }
    knit::StretchResult result;
    try {
      if (o->use_sheet) {
        o->sheet.stretch = o->stretch;
        if (!o->fit.empty()) {
          const knit::SheetFit fit = knit::fit_sheet_material(from, o->fit, o->sheet);
          o->sheet.material = fit.material;
          o->sheet.fit = fit.report;
          if (!o->quiet) {
            // a copy: a key it lacks reads as null ("not measured"), not as undefined
            nlohmann::json m = fit.report["material"];
            std::cerr << "sheet fitted: k_course "
                      << quantity(m["k_stretch_u_dyn_per_cm"], "dyn/cm") << ", k_wale "
                      << quantity(m["k_stretch_v_dyn_per_cm"], "dyn/cm") << ", k_shear "
                      << quantity(m["k_shear_dyn_per_cm"], "dyn/cm") << ", k_bend "
                      << quantity(m["k_bend_erg"], "erg") << "\n";
          }
        }
        result = knit::stretch_sheet(from, o->sheet);
      } else {
        for (const std::string& caveat : knit::stretch_caveats(o->stretch))
          std::cerr << "knitsim: warning: " << caveat << "\n";
        result = knit::stretch_knit(from, o->stretch);
      }
    } catch (...) {
      if (!temp.empty()) std::remove(temp.c_str());
      throw;
    }
    if (!temp.empty()) {
      knit::claim_run_output((std::filesystem::path(o->out) / "relaxed.kstate").string());
      std::filesystem::copy_file(temp, std::filesystem::path(o->out) / "relaxed.kstate",
                                 std::filesystem::copy_options::overwrite_existing);
      std::remove(temp.c_str());
    }
    if (o->use_sheet) {
      const auto& sh = result.report.summary["sheet"];
      std::cout << "status " << result.report.summary["status"].get<std::string>() << ": "
                << result.curve.size() << " equilibria of the sheet (" << quantity(sh["nodes"])
                << " nodes), " << quantity(sh["newton_iterations"]) << " Newton iterations in "
                << quantity(result.report.summary["wall_time_s"], "s") << "; outputs in " << o->out
                << "/\n";
      if (!result.report.message.empty()) std::cerr << "knitsim: " << result.report.message << "\n";
      end_if_interrupted(result.report);
    } else {
      print_report(result.report, o->out);
      end_if_interrupted(result.report);
    }
    // not const: a measure the summary lacks reads as null ("not measured")
    auto& m = result.report.summary["stretch"];
    // a pull that stopped (unstable) says where
    double reached = 0;
    for (const auto& s : result.curve) reached = std::max(reached, s.strain);
    if (m.contains("stopped"))
      std::cout << "stopped at the load limit: "
                << quantity(m["stopped"]["force_moving_dyn"], "dyn")
                << " on the moving clamp (limit " << quantity(o->stretch.max_force, "dyn")
                << ") at strain " << quantity(m["stopped"]["strain"]) << " of "
                << quantity(o->stretch.to_strain) << ", pulled " << o->direction;
    else if (result.report.status == knit::StepStatus::OK || result.curve.empty())
      std::cout << "stretched " << o->direction << " to strain " << quantity(o->stretch.to_strain);
    else
      std::cout << "stopped at strain " << quantity(reached) << " of "
                << quantity(o->stretch.to_strain) << " ("
                << result.report.summary.value("status", std::string("failed")) << "), pulled "
                << o->direction;
    // the stiffnesses are slopes over a tenth of the pull: a short pull has too few
    // samples for them (null in the summary)
    const nlohmann::json k0 = m["stiffness_small_strain"], k1 = m["stiffness_end"];
    std::string stiffness = "stiffness not measured (too few samples in the pull)";
    if (k0.is_number() || k1.is_number())
      stiffness = "stiffness " + quantity(k0) + " → " + quantity(k1) + " dyn per unit strain";
    std::cout << ": initial clamp separation " << quantity(result.initial_separation, "cm")
              << ", max force " << quantity(m["max_force_dyn"], "dyn") << ", " << stiffness
              << "; stretch.csv in " << o->out << "/\n";
    if (result.report.status != knit::StepStatus::OK) throw RunFailed();
  });
}

const bool stretch_added = add_command(60, register_stretch);

}  // namespace knitsim
