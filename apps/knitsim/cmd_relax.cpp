// knitsim relax PATTERN --rows R --cols C --out DIR
// Builds the interlocked yarn of a knit pattern and relaxes it to rest (MODEL.md §6).
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "common.hpp"
#include "knit/analysis/fabric_shape.hpp"
#include "knit/filters/nonrigid_damping.hpp"
#include "knit/io/import.hpp"
#include "knit/io/state_file.hpp"
#include "knit/pattern/generator.hpp"
#include "knit/pattern/pattern.hpp"
#include "knit/solver/relaxation.hpp"

namespace knitsim {

namespace {

// the generated yarn ends lie a yarn diameter from the points they are glued to; the gap
// closes over this time (s) at the start of the relaxation
constexpr double GLUE_CLOSE_TIME = 0.05;

// Relaxes yarns imported from a file: no stitch coordinates, so no non-rigid damping
// regions and no shape measures; the relaxation parameters otherwise apply unchanged.
template <class Opts>
void relax_imported(Opts& o) {
  namespace fs = std::filesystem;
  knit::Params params = knit::Params::relaxation();
  params.gravity.setZero();
  params.contact_points = o.contact_points;
  params.k_global = o.damping.k_global;
  if (!o.time_step_given) o.relax.time_step = 1.0 / 25000;
  knit::ModelBuilder builder;
  for (const knit::ImportedYarn& y : knit::import_yarns(o.from, o.import))
    builder.add_yarn(y.control_points);
  params.radius = o.import.radius;
  const knit::Model model = builder.build(params, o.shrink);
  auto control = make_thread_control(o.threads);
  knit::State state;
  state.q = builder.positions();
  state.v = Eigen::VectorXd::Zero(state.q.size());
  fs::create_directories(o.out);
  knit::write_state_file((fs::path(o.out) / "initial.kstate").string(),
                         knit::make_state_file(model, state));
  knit::Simulator sim(model);
  o.relax.out_dir = o.out;
  o.relax.progress = !o.quiet;
  o.relax.write_frames = !o.no_frames;
  const knit::RunReport report = knit::relax(sim, state, o.relax,
                                             {{"from", o.from},
                                              {"shrink", o.shrink},
                                              {"contact_points", o.contact_points},
                                              {"k_global", params.k_global}});
  fs::copy_file(fs::path(o.out) / "final.kstate", fs::path(o.out) / "relaxed.kstate",
                fs::copy_options::overwrite_existing);
  print_report(report, o.out);
  export_run(o.out, o.export_format);
  if (report.status != knit::StepStatus::OK) throw RunFailed();
}

knit::State generated_state(const knit::GeneratedKnit& knit) {
  knit::State state;
  state.q =
      Eigen::Map<const Eigen::VectorXd>(knit.control_points.data(), knit.control_points.size());
  state.v = Eigen::VectorXd::Zero(state.q.size());
  return state;
}

// The state of an earlier relaxation of the same knit: same control point count and the
// same stitch of every segment, or an error naming the file and what differs.
knit::State resumed_state(const std::string& path, const knit::GeneratedKnit& knit,
                          const std::string& pattern, bool in_the_round) {
  namespace fs = std::filesystem;
  // the run that wrote the file names its pattern in its summary (DIR/ or DIR/frames/)
  for (const fs::path& dir :
       {fs::path(path).parent_path(), fs::path(path).parent_path().parent_path()}) {
    std::ifstream in(dir / "summary.json");
    if (!in) continue;
    const nlohmann::json s = nlohmann::json::parse(in, nullptr, false);
    if (s.is_object() && s.contains("pattern") && s["pattern"].is_string() &&
        s["pattern"].get<std::string>() != pattern)
      throw std::invalid_argument("--resume " + path + ": it was relaxed from pattern " +
                                  s["pattern"].get<std::string>() + " (" +
                                  (dir / "summary.json").string() + "), not " + pattern);
    if (s.is_object() && s.contains("in_the_round") && s["in_the_round"].is_boolean() &&
        s["in_the_round"].get<bool>() != in_the_round)
      throw std::invalid_argument("--resume " + path + ": it was knitted " +
                                  (in_the_round ? "flat" : "in the round") + " (" +
                                  (dir / "summary.json").string() + "); give " +
                                  (in_the_round ? "no --round" : "--round") + " to go on");
    break;
  }
  const knit::StateFile f = knit::read_state_file(path);
  const int expected = static_cast<int>(knit.control_points.cols());
  if (f.yarn_cp_counts.size() != 1 || f.num_cp() != expected)
    throw std::invalid_argument("--resume " + path + ": it holds " +
                                std::to_string(f.yarn_cp_counts.size()) + " yarn(s) and " +
                                std::to_string(f.num_cp()) + " control points, but " + pattern +
                                " at this size has 1 yarn and " + std::to_string(expected) +
                                " (give the --rows, --cols and options of the first run)");
  for (size_t i = 0; i < f.stitch.size(); ++i)
    if (f.stitch[i].row != knit.stitch[i].row || f.stitch[i].col != knit.stitch[i].col)
      throw std::invalid_argument("--resume " + path + ": segment " + std::to_string(i) +
                                  " belongs to stitch (" + std::to_string(f.stitch[i].row) + ", " +
                                  std::to_string(f.stitch[i].col) + "), but to (" +
                                  std::to_string(knit.stitch[i].row) + ", " +
                                  std::to_string(knit.stitch[i].col) + ") in " + pattern);
  return f.state;
}

}  // namespace

void register_relax(CLI::App& app) {
  struct Opts {
    std::string pattern, out, from, resume, export_format;
    knit::ImportOptions import;
    knit::KnitOptions knit;
    knit::RelaxOptions relax;
    int threads = 0;
    int contact_points = 10;
    double shrink = knit::RELAX_SHRINK;
    knit::Params damping = knit::Params::relaxation();
    bool quiet = false, no_frames = false;
    bool time_step_given = false;
  };
  auto o = std::make_shared<Opts>();
  o->knit.rows = 12;
  o->knit.cols = 12;
  CLI::App* cmd =
      app.add_subcommand("relax", "build a knit pattern's interlocked yarn and relax it to rest");
  cmd->add_option("pattern", o->pattern,
                  "built-in pattern (stockinette, garter, rib2x2, rib1x1, seed, "
                  "reverse_stockinette) or a chart file (k/p per stitch, last line = row 0)");
  cmd->add_option("--from", o->from,
                  "relax yarns imported from a .yarns, .bcc or .obj file instead of a pattern");
  cmd->add_option("--resume", o->resume,
                  "go on relaxing from a state written by an earlier `relax` of the same "
                  "pattern and size (its relaxed.kstate or a frame); --max-time is then added")
      ->check(CLI::ExistingFile);
  cmd->add_option(
         "--scale", o->import.scale,
         "with --from: multiply coordinates (default: the file's yarn radius becomes 0.125 cm)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out,-o", o->out, "output directory")->required();
  cmd->add_option("--rows", o->knit.rows, "rows (courses)")->check(CLI::PositiveNumber);
  cmd->add_option("--cols", o->knit.cols, "stitches per row")->check(CLI::PositiveNumber);
  cmd->add_option("--segments-per-stitch", o->knit.segments_per_stitch,
                  "spline segments per stitch")
      ->check(CLI::Range(4, 64));
  cmd->add_flag("--round", o->knit.in_the_round, "knit in the round (a tube)");
  cmd->add_option("--stitch-size", o->knit.stitch_size_cm,
                  "yarn length per stitch before shrinking (cm; 0 = default for the yarn)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--contact-points", o->contact_points, "contact quadrature points per segment")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--shrink", o->shrink, "rest-length shrink factor c")
      ->check(CLI::Range(0.5, 1.0));
  cmd->add_option("--k-global", o->damping.k_global,
                  "global damping k_global (g/s; default 0.15 for patterns, 1.5 with --from)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--alpha-small", o->damping.alpha_small,
                  "non-rigid damping of the small regions per step (default 0.3)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--alpha-large", o->damping.alpha_large,
                  "non-rigid damping of the large regions per step (default 0.3)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option(
         "--time-step", o->relax.time_step,
         "s (default 1/11800; 1/25000 with --from: imported swatches start tightly packed)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-time", o->relax.max_time, "simulated seconds at most")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--ke-threshold", o->relax.ke_per_length,
                  "rest when kinetic energy per yarn length falls below (erg/cm)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--check-every", o->relax.check_every, "steps between rest checks and states")
      ->check(CLI::PositiveNumber);
  add_threads_option(cmd, o->threads);
  cmd->add_flag("--no-frames", o->no_frames, "write only the initial and relaxed states");
  cmd->add_flag("--quiet,-q", o->quiet, "no progress line");
  add_export_option(cmd, o->export_format);
  cmd->callback([o, cmd]() {
    if (o->from.empty() == o->pattern.empty())
      throw std::invalid_argument("relax: give either a PATTERN or --from FILE");
    o->time_step_given = cmd->count("--time-step") > 0;
    if (cmd->count("--k-global") == 0 && o->from.empty())
      o->damping.k_global = knit::RELAX_K_GLOBAL;
    if (!o->from.empty()) return relax_imported(*o);
    namespace fs = std::filesystem;
    // everything is validated before anything is written
    const knit::Pattern pattern = knit::load_pattern(o->pattern);
    const knit::GeneratedKnit knit = knit::generate_knit(pattern, o->knit);
    knit::Params params = knit::Params::relaxation();
    params.gravity.setZero();  // the sample relaxes in free space
    params.contact_points = o->contact_points;
    params.k_global = o->damping.k_global;
    params.alpha_small = o->damping.alpha_small;
    params.alpha_large = o->damping.alpha_large;
    // a resumed state carries its time, so its glues go on closing where they were
    const knit::Model model = knit::build_knit_model(knit, params, o->shrink, GLUE_CLOSE_TIME);
    knit::State state = o->resume.empty()
                            ? generated_state(knit)
                            : resumed_state(o->resume, knit, o->pattern, o->knit.in_the_round);
    auto control = make_thread_control(o->threads);
    fs::create_directories(o->out);
    knit::write_state_file((fs::path(o->out) / "initial.kstate").string(),
                           knit::make_state_file(model, state));
    const knit::FabricShape initial = knit::measure_fabric(model, generated_state(knit).q);

    knit::Simulator sim(model);
    sim.add_filter(std::make_unique<knit::NonRigidDampingFilter>(
        model, params.alpha_small, params.alpha_large, o->knit.in_the_round));
    o->relax.out_dir = o->out;
    o->relax.progress = !o->quiet;
    o->relax.write_frames = !o->no_frames;
    nlohmann::json extra = {{"pattern", o->pattern},
                            {"rows", o->knit.rows},
                            {"cols", o->knit.cols},
                            {"in_the_round", o->knit.in_the_round},
                            {"segments_per_stitch", o->knit.segments_per_stitch},
                            {"shrink", o->shrink},
                            {"contact_points", o->contact_points},
                            {"resumed_from", o->resume},
                            {"k_global", params.k_global},
                            {"alpha_small", params.alpha_small},
                            {"alpha_large", params.alpha_large},
                            {"generated",
                             {{"stitch_width_cm", knit.stitch_width_cm},
                              {"row_height_cm", knit.row_height_cm},
                              {"loop_depth_cm", knit.loop_depth_cm},
                              {"loop_length_cm", knit.loop_length_cm},
                              {"min_distance_ratio", knit.min_distance_ratio},
                              {"shape", knit::to_json(initial)}}}};
    const knit::RunReport report =
        knit::relax(sim, state, o->relax, extra,
                    [&](knit::Simulator&, const knit::State& st, nlohmann::json& summary) {
                      const nlohmann::json shape = knit::to_json(knit::measure_fabric(model, st.q));
                      for (const auto& [k, v] : shape.items()) summary[k] = v;
                    });
    fs::copy_file(fs::path(o->out) / "final.kstate", fs::path(o->out) / "relaxed.kstate",
                  fs::copy_options::overwrite_existing);
    print_report(report, o->out);
    export_run(o->out, o->export_format);
    const auto& s = report.summary;
    std::cout << "relaxed " << o->pattern << " " << o->knit.rows << "x" << o->knit.cols << ": "
              << (s["relaxed"].get<bool>() ? "at rest" : "time limit reached before rest")
              << "; course " << s["course_extent_cm"].get<double>() << " cm, wale "
              << s["wale_extent_cm"].get<double>() << " cm (along the fabric "
              << s["course_length_cm"].get<double>() << " × " << s["wale_length_cm"].get<double>()
              << " cm), edge curl " << s["edge_curl"].get<double>() << "\n";
    if (report.status != knit::StepStatus::OK) throw RunFailed();
  });
}

}  // namespace knitsim
