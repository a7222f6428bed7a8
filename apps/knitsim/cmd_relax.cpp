// knitsim relax PATTERN --rows R --cols C --out DIR
// Builds the interlocked yarn of a knit pattern and relaxes it to rest (MODEL.md §6): a
// thin adapter over the relax_knit / relax_yarns recipes (src/knit/recipes/relax_knit.hpp),
// which hold the recipe and its defaults.
#include <cstdio>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "common.hpp"
#include "knit/io/state_file.hpp"
#include "knit/pattern/knitout.hpp"
#include "knit/recipes/relax_knit.hpp"
#include "knit/util/run_dir.hpp"

namespace knitsim {

void register_relax(CLI::App& app) {
  struct Opts {
    std::string pattern, out, from, resume, export_format;
    knit::RelaxKnitOptions knit;
    knit::RelaxYarnsOptions yarns;
    knit::RelaxOptions run;
    // the material's and the solver's options start at the recipe's own values
    knit::Material material = knit::relax_knit_params().material;
    int contact_points = knit::relax_knit_params().discretisation.contact_points;
    double end_mass_floor = knit::relax_knit_params().discretisation.end_mass_floor;
    double time_step = knit::relax_knit_params().solver.time_step;
    std::string integrator = knit::integrator_name(knit::relax_knit_params().solver.integrator);
    double contact_reuse = knit::relax_knit_params().solver.contact_reuse;
    double contact_solve_tolerance = knit::relax_knit_params().solver.contact_solve_tolerance;
    bool implicit_bending = knit::relax_knit_params().solver.implicit_bending;
    bool refuse_crossings = knit::relax_knit_params().solver.refuse_crossings;
    int max_step_halvings = knit::relax_knit_params().solver.max_step_halvings;
    double shrink = knit::RELAX_SHRINK;
    int threads = 0;
    bool quiet = false, no_frames = false, overwrite = false, fire = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd =
      app.add_subcommand("relax", "build a knit pattern's interlocked yarn and relax it to rest");
  const knit::Params yarns = knit::relax_yarns_params();
  add_text(cmd, "pattern", o->pattern,
           "built-in pattern (stockinette, garter, rib2x2, rib1x1, seed, reverse_stockinette), a "
           "chart file (k/p per stitch, last line = row 0) or a knitout program (.k: its size "
           "and flat/round are the program's)",
           "name or path", "none: give a PATTERN or --from (with --resume: the state's)");
  add_path(cmd, "--from", o->from,
           "relax yarns imported from a .yarns, .bcc or .obj file instead of a pattern",
           "none (a PATTERN)");
  add_path(cmd, "--resume", o->resume,
           "go on relaxing from a state written by an earlier `relax` (its relaxed.kstate or a "
           "frame); its pattern, size and options are the defaults: the knit's, and how it was "
           "being relaxed (--fire, the integrator, time step, contact options, damping and rest "
           "test); --max-time is then added",
           "none (from the generated knit)")
      ->check(existing_file());
  add_number(cmd, "--scale", o->yarns.import.scale, "with --from: multiply the file's coordinates",
             "factor", positive(1e6),
             "automatic: the file's yarn radius becomes " +
                 knit::short_number(o->yarns.import.radius) + " cm");
  add_out_option(cmd, o->out, "output directory");
  add_overwrite_flag(cmd, o->overwrite);
  add_size_options(
      cmd, o->knit.knit.rows, o->knit.knit.cols, "rows (courses)",
      "stitches per row (at least " + std::to_string(knit::MIN_ROUND_COLS) + " in the round)",
      " (a knitout program: its own)");
  add_integer(cmd, "--segments-per-stitch", o->knit.knit.segments_per_stitch,
              "spline segments per stitch", knit::MIN_SEGMENTS_PER_STITCH,
              knit::MAX_SEGMENTS_PER_STITCH, "count");
  cmd->add_flag("--round", o->knit.knit.in_the_round, "knit in the round (a tube)");
  cmd->add_flag("--bind-off", o->knit.knit.bind_off,
                "bind off the last row: tie each of its loops to the loop below where they cross, "
                "as a sewn bind-off does, so that its loops cannot ladder when pulled");
  cmd->add_flag("--cast-on", o->knit.knit.cast_on,
                "cast on the first row: tie each loop of the second row where its legs cross the "
                "first row's loop, so that a pull cannot draw the first row's yarn out");
  add_number(cmd, "--stitch-size", o->knit.knit.stitch_size_cm,
             "yarn length per stitch before shrinking (working range " +
                 knit::short_number(knit::MIN_STITCH_SIZE_RADII) + "–" +
                 knit::short_number(knit::MAX_STITCH_SIZE_RADII) + " yarn radii)",
             "cm", closed(0, 1e3), "0 (the generator's own for the yarn radius)");
  add_number(cmd, "--shrink", o->shrink, "rest-length shrink factor c (docs/model.md §6)", "factor",
             closed(knit::MIN_SHRINK, knit::MAX_SHRINK));
  add_number(cmd, "--k-global", o->material.k_global, "global (mass-proportional) damping", "g/s",
             param("k_global"),
             number_text(o->material.k_global) + " (" + number_text(yarns.material.k_global) +
                 " with --from)");
  add_damping_options(cmd, o->material);
  add_time_step_option(cmd, o->time_step,
                       number_text(o->time_step) + ", " + number_text(yarns.solver.time_step) +
                           " with --from (imported swatches start tightly packed)");
  add_integrator_option(cmd, o->integrator);
  add_implicit_bending_option(cmd, o->implicit_bending, true);
  add_refuse_crossings_option(cmd, o->refuse_crossings, true);
  add_contact_solve_tolerance_option(cmd, o->contact_solve_tolerance);
  add_contact_reuse_option(cmd, o->contact_reuse);
  add_max_step_halvings_option(cmd, o->max_step_halvings);
  add_end_mass_floor_option(cmd, o->end_mass_floor);
  add_contact_points_option(cmd, o->contact_points);
  add_number(cmd, "--contact-reuse-widen", o->run.contact_reuse_widen,
             "with --contact-reuse: widen its distance up to this factor while the knit is far "
             "from rest, by the last check's force residual over --contact-reuse-widen-residual "
             "(2 took 42×32 FIRE relaxations to rest in 6–16 % less time)",
             "factor", closed(1, 100), number_text(o->run.contact_reuse_widen) + " (no widening)");
  add_number(cmd, "--contact-reuse-widen-residual", o->run.contact_reuse_widen_residual,
             "the force residual above which --contact-reuse-widen widens: the reuse distance "
             "is ρ r · clamp(R / this, 1, widen)",
             "cm/s²", positive(1e12));
  add_number(cmd, "--max-time", o->run.max_time,
             "simulated time at most (with --resume: this much more)", "s",
             positive(knit::MAX_DURATION));
  add_number(cmd, "--ke-threshold", o->run.ke_per_length,
             "rest when the kinetic energy per yarn length falls below this", "erg/cm",
             positive(1e12));
  add_number(
      cmd, "--residual", o->run.force_residual,
      "rest when the net force per unit mass falls below this (g = 981 cm/s²): the "
      "force-residual test instead of --ke-threshold",
      "cm/s²", positive(1e12),
      "none: the --ke-threshold test (" + number_text(knit::RELAX_FIRE_RESIDUAL) + " with --fire)");
  cmd->add_flag("--fire,!--no-fire", o->fire,
                "relax by minimisation (FIRE) instead of damped dynamics: no global or non-rigid "
                "damping, the motion steered downhill; rest by the force residual (--no-fire: "
                "damped dynamics, where a resumed state was relaxed with --fire)");
  add_integer(cmd, "--check-every", o->run.check_every, "steps between rest checks and states", 1,
              1'000'000'000, "steps");
  add_threads_option(cmd, o->threads);
  cmd->add_flag("--no-frames", o->no_frames, "write only the initial and relaxed states");
  add_number(cmd, "--checkpoint-every", o->run.checkpoint_every_s,
             "with --no-frames: wall-clock seconds between checkpoints (the state written to "
             "DIR/final.kstate and the summary's resume_command, so that a run killed outright "
             "goes on from there); 0: none",
             "s (wall clock)", closed(0, 1e9));
  add_quiet_flag(cmd, o->quiet);
  add_check_crossings_flag(cmd, o->run.check_crossings);
  add_export_option(cmd, o->export_format);
  cmd->callback([o, cmd]() {
    auto given = [&](const char* name) { return cmd->count(name) > 0; };
    bool fire_from_state = false;  // --fire not given, but the resumed state was so relaxed
    if (!o->resume.empty() && o->from.empty()) {
      // a state written by `relax` says what it is: the knit's options default to its own
      const knit::StateFile f = knit::read_state_file(o->resume);
      o->run.resumed_totals = f.run;  // (a run that goes on in its directory goes on adding up)
      if (f.knit) {
        if (o->pattern.empty()) o->pattern = f.knit->pattern;
        if (!given("--rows")) o->knit.knit.rows = f.knit->rows;
        if (!given("--cols")) o->knit.knit.cols = f.knit->cols;
        if (!given("--round")) o->knit.knit.in_the_round = f.knit->in_the_round;
        if (!given("--segments-per-stitch"))
          o->knit.knit.segments_per_stitch = f.knit->segments_per_stitch;
        if (!given("--stitch-size")) o->knit.knit.stitch_size_cm = f.knit->stitch_size_cm;
        if (!given("--bind-off")) o->knit.knit.bind_off = f.knit->bind_off;
        if (!given("--cast-on")) o->knit.knit.cast_on = f.knit->cast_on;
        if (!given("--shrink")) o->shrink = f.knit->shrink;
        // and the relaxation goes on as it went (method, solver, rest test), unless told
        if (f.knit->relaxation) {
          const knit::KnitRelaxSettings& s = *f.knit->relaxation;
          fire_from_state = s.fire && !given("--fire");
          if (!given("--fire")) o->fire = s.fire;
          if (!given("--integrator"))
            o->integrator = knit::integrator_name(s.params.solver.integrator);
          if (!given("--time-step")) o->time_step = s.params.solver.time_step;
          if (!given("--implicit-bending")) o->implicit_bending = s.params.solver.implicit_bending;
          if (!given("--refuse-crossings")) o->refuse_crossings = s.params.solver.refuse_crossings;
          if (!given("--contact-solve-tolerance"))
            o->contact_solve_tolerance = s.params.solver.contact_solve_tolerance;
          if (!given("--contact-reuse")) o->contact_reuse = s.params.solver.contact_reuse;
          if (!given("--max-step-halvings"))
            o->max_step_halvings = s.params.solver.max_step_halvings;
          if (!given("--contact-points"))
            o->contact_points = s.params.discretisation.contact_points;
          if (!given("--end-mass-floor"))
            o->end_mass_floor = s.params.discretisation.end_mass_floor;
          if (!given("--k-global")) o->material.k_global = s.params.material.k_global;
          if (!given("--alpha-small")) o->material.alpha_small = s.params.material.alpha_small;
          if (!given("--alpha-large")) o->material.alpha_large = s.params.material.alpha_large;
          if (!given("--ke-threshold")) o->run.ke_per_length = s.ke_per_length;
          if (!given("--residual")) o->run.force_residual = s.force_residual;
          if (!given("--check-every")) o->run.check_every = s.check_every;
          if (!given("--contact-reuse-widen")) o->run.contact_reuse_widen = s.contact_reuse_widen;
          if (!given("--contact-reuse-widen-residual"))
            o->run.contact_reuse_widen_residual = s.contact_reuse_widen_residual;
          // the file's contact reuse goes with its integrator when another is asked for,
          // and its widening with the reuse
          if (given("--integrator") && o->integrator != "imex-contact" && !given("--contact-reuse"))
            o->contact_reuse = 0;
          if (o->contact_reuse == 0 && !given("--contact-reuse-widen"))
            o->run.contact_reuse_widen = 1;
        }
      } else if (o->pattern.empty()) {
        throw std::invalid_argument("--resume " + o->resume +
                                    ": the file does not say which knit it holds (written "
                                    "before .kstate version 2): give the PATTERN and its options");
      }
    }
    if (o->from.empty() == o->pattern.empty())
      throw std::invalid_argument("relax: give either a PATTERN or --from FILE");
    if (o->fire) {
      if (!o->from.empty())
        throw std::invalid_argument("--fire: relaxes knit patterns only, not yarns --from a file");
      for (const char* damping : {"--k-global", "--alpha-small", "--alpha-large"})
        if (given(damping))
          throw std::invalid_argument(
              std::string(damping) + ": a FIRE relaxation (--fire) has no damping to set" +
              (fire_from_state ? std::string(" (--resume ") + o->resume +
                                     " was relaxed with --fire; --no-fire goes on by damped "
                                     "dynamics)"
                               : std::string()));
    }
    if (o->resume.empty() && knit::is_knitout_path(o->pattern)) {
      // a knitting-machine program knits what it says: its size is the default
      const knit::KnitoutPiece piece = knit::load_knitout(o->pattern);
      if (!given("--rows")) o->knit.knit.rows = piece.rows();
      if (!given("--cols")) o->knit.knit.cols = piece.cols();
      if (!given("--round")) o->knit.knit.in_the_round = piece.in_the_round;
    }
    o->run.out_dir = o->out;
    o->run.overwrite = o->overwrite;
    o->run.continue_in_place = knit::resumes_in_place(o->resume, o->out);
    // an interrupted run goes on with this command, for the time it had left
    const std::vector<std::pair<std::string, std::string>> replace = {
        {std::string("--max-time"), std::string("{time_left}")}};
    o->run.resume_command = resume_command(o->out, replace);
    o->run.progress = !o->quiet;
    o->run.write_frames = !o->no_frames;
    auto control = make_thread_control(o->threads);
    knit::RelaxResult result;
    // the solver's options, the same for imported yarns and for a knit
    auto set_solver = [&](knit::Params& p) {
      p.solver.integrator = knit::parse_integrator(o->integrator);
      p.solver.contact_reuse = o->contact_reuse;
      p.solver.contact_solve_tolerance = o->contact_solve_tolerance;
      p.solver.implicit_bending = o->implicit_bending;
      p.solver.refuse_crossings = o->refuse_crossings;
      p.solver.max_step_halvings = o->max_step_halvings;
      p.discretisation.contact_points = o->contact_points;
      p.discretisation.end_mass_floor = o->end_mass_floor;
    };
    if (!o->from.empty()) {
      // the recipe's defaults for imported yarns, overridden by what was given
      knit::Params& p = o->yarns.params;
      if (given("--k-global")) p.material.k_global = o->material.k_global;
      if (given("--alpha-small")) p.material.alpha_small = o->material.alpha_small;
      if (given("--alpha-large")) p.material.alpha_large = o->material.alpha_large;
      if (given("--time-step")) p.solver.time_step = o->time_step;
      set_solver(p);
      o->yarns.shrink = o->shrink;
      o->yarns.run = o->run;
      add_provenance(o->yarns.extra);
      result = knit::relax_yarns(o->from, o->yarns);
    } else {
      knit::Params& p = o->knit.params;
      p.material = o->material;
      p.solver.time_step = o->time_step;
      set_solver(p);
      o->knit.shrink = o->shrink;
      o->knit.fire = o->fire;
      o->knit.run = o->run;
      knit::State resumed;
      if (!o->resume.empty()) {
        resumed = knit::read_resumed_knit_state(o->resume, o->pattern, o->knit.knit);
        o->knit.resume = &resumed;
      }
      o->knit.extra["resumed_from"] = o->resume;
      add_provenance(o->knit.extra);
      result = knit::relax_knit(o->pattern, o->knit);
    }
    const knit::RunReport& report = result.report;
    print_report(report, o->out);
    end_if_interrupted(report);
    export_run(o->out, o->export_format);
    if (o->from.empty()) {
      const auto& s = report.summary;
      std::cout << "relaxed " << o->pattern << " " << o->knit.knit.rows << "x" << o->knit.knit.cols
                << ": "
                << (s.value("relaxed", false) ? "at rest" : "time limit reached before rest")
                << "; course " << quantity(s["course_extent_cm"], "cm") << ", wale "
                << quantity(s["wale_extent_cm"], "cm") << " (along the fabric "
                << quantity(s["course_length_cm"]) << " × " << quantity(s["wale_length_cm"], "cm")
                << "), edge curl " << quantity(s["edge_curl"]) << "\n";
    }
    if (report.status != knit::StepStatus::OK) throw RunFailed();
  });
}

const bool relax_added = add_command(20, register_relax);

}  // namespace knitsim
