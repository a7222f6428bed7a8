#include "knit/recipes/relax_knit.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>

#include "knit/analysis/fabric_shape.hpp"
#include "knit/filters/fire.hpp"
#include "knit/filters/nonrigid_damping.hpp"
#include "knit/io/state_file.hpp"
#include "knit/pattern/knitout.hpp"
#include "knit/pattern/pattern.hpp"
#include "knit/util/input_file.hpp"
#include "knit/util/run_dir.hpp"

namespace knit {

namespace fs = std::filesystem;

Params relax_knit_params() {
  Params p = Params::relaxation();
  p.gravity.setZero();
  p.material.k_global = RELAX_K_GLOBAL;
  return p;
}

Params relax_yarns_params() {
  Params p = Params::relaxation();
  p.gravity.setZero();
  p.solver.time_step = 1.0 / 25000;
  return p;
}

namespace {

State generated_state(const GeneratedKnit& knit) {
  State state;
  state.q =
      Eigen::Map<const Eigen::VectorXd>(knit.control_points.data(), knit.control_points.size());
  state.v = Eigen::VectorXd::Zero(state.q.size());
  return state;
}

// after a run that went well: relaxed.kstate beside final.kstate
void copy_relaxed(const std::string& out_dir, const RunReport& report) {
  if (out_dir.empty()) return;
  if (report.status != StepStatus::OK) {
    fs::remove(fs::path(out_dir) / "relaxed.kstate");
    return;
  }
  claim_run_output((fs::path(out_dir) / "relaxed.kstate").string());
  fs::copy_file(fs::path(out_dir) / "final.kstate", fs::path(out_dir) / "relaxed.kstate",
                fs::copy_options::overwrite_existing);
}

}  // namespace

void check_shrink(double shrink) {
  if (!std::isfinite(shrink) || shrink < MIN_SHRINK || shrink > MAX_SHRINK)
    throw std::invalid_argument("shrink = " + short_number(shrink) +
                                " is outside its working range [" + short_number(MIN_SHRINK) +
                                ", " + short_number(MAX_SHRINK) + "]");
}

void check_knit_relaxation(const KnitOptions& k, double shrink, const Params& params) {
  check_shrink(shrink);
  if (k.rows < 2 || k.cols < 2)
    throw std::invalid_argument("rows = " + std::to_string(k.rows) +
                                ", cols = " + std::to_string(k.cols) +
                                ": a knit needs at least 2 rows and 2 columns");
  if (k.in_the_round && k.cols < MIN_ROUND_COLS)
    throw std::invalid_argument("cols = " + std::to_string(k.cols) +
                                ": a tube knit in the round "
                                "needs at least " +
                                std::to_string(MIN_ROUND_COLS) + " stitches around");
  if (k.segments_per_stitch < MIN_SEGMENTS_PER_STITCH ||
      k.segments_per_stitch > MAX_SEGMENTS_PER_STITCH)
    throw std::invalid_argument(
        "segments-per-stitch = " + std::to_string(k.segments_per_stitch) +
        " is outside its working range [" + std::to_string(MIN_SEGMENTS_PER_STITCH) + ", " +
        std::to_string(MAX_SEGMENTS_PER_STITCH) + "] (outside it the relaxation goes unstable)");
  const double r = params.material.radius;
  if (!std::isfinite(k.stitch_size_cm) ||
      (k.stitch_size_cm != 0 && (k.stitch_size_cm < MIN_STITCH_SIZE_RADII * r ||
                                 k.stitch_size_cm > MAX_STITCH_SIZE_RADII * r)))
    throw std::invalid_argument(
        "stitch-size = " + short_number(k.stitch_size_cm) + " cm is outside its working range [" +
        short_number(MIN_STITCH_SIZE_RADII * r) + ", " + short_number(MAX_STITCH_SIZE_RADII * r) +
        "] cm for yarn of radius " + short_number(r) + " cm (0 = the default)");
  const double segments =
      static_cast<double>(k.rows) * k.cols * k.segments_per_stitch + 2.0 * k.rows * 8;
  if (segments > static_cast<double>(MAX_KNIT_SEGMENTS))
    throw std::invalid_argument("rows × cols = " + std::to_string(k.rows) + " × " +
                                std::to_string(k.cols) + " would make " + short_number(segments) +
                                " spline segments, more than knitsim accepts (" +
                                short_number(static_cast<double>(MAX_KNIT_SEGMENTS)) + ")");
  const double need =
      segments * RELAX_BYTES_PER_SEGMENT * (params.discretisation.contact_points / 10.0 + 1) / 2;
  const double have = available_memory_bytes();
  if (have > 0 && need > have)
    throw std::invalid_argument("rows × cols = " + std::to_string(k.rows) + " × " +
                                std::to_string(k.cols) + " needs about " + format_bytes(need) +
                                " of memory, and this machine has " + format_bytes(have) +
                                " available");
}

void check_knitout_size(const std::string& pattern, const KnitOptions& knit) {
  if (!is_knitout_path(pattern) || !std::filesystem::exists(pattern)) return;
  const KnitoutPiece piece = load_knitout(pattern);
  if (piece.rows() != knit.rows || piece.cols() != knit.cols ||
      piece.in_the_round != knit.in_the_round) {
    const std::string size = std::to_string(piece.rows()) + " rows × " +
                             std::to_string(piece.cols()) + " columns " +
                             (piece.in_the_round ? "in the round" : "flat");
    throw std::invalid_argument(pattern + ": the program knits " + size +
                                "; relax it at that size (rows " + std::to_string(piece.rows()) +
                                ", cols " + std::to_string(piece.cols()) +
                                (piece.in_the_round ? ", in the round)" : ", flat)"));
  }
}

State read_resumed_knit_state(const std::string& path, const std::string& pattern,
                              const KnitOptions& options) {
  const GeneratedKnit knit = generate_knit(load_pattern(pattern), options);
  const bool in_the_round = options.in_the_round;
  const StateFile f = read_state_file(path);
  if (f.knit) {
    // files written since the knit block exists say what they are
    if (f.knit->pattern != pattern)
      throw std::invalid_argument("--resume " + path + ": it was relaxed from pattern " +
                                  f.knit->pattern + ", not " + pattern);
    if (f.knit->in_the_round != in_the_round)
      throw std::invalid_argument("--resume " + path + ": it was knitted " +
                                  (in_the_round ? "flat" : "in the round") + "; give " +
                                  (in_the_round ? "no --round" : "--round") + " to go on");
    if (f.knit->bind_off != options.bind_off)
      throw std::invalid_argument(
          "--resume " + path + ": it was knitted " + (options.bind_off ? "without" : "with") +
          " a bind-off; give " + (options.bind_off ? "no --bind-off" : "--bind-off") + " to go on");
    if (f.knit->cast_on != options.cast_on)
      throw std::invalid_argument("--resume " + path + ": it was knitted " +
                                  (options.cast_on ? "without" : "with") + " a cast-on; give " +
                                  (options.cast_on ? "no --cast-on" : "--cast-on") + " to go on");
  } else {
    // older files: the run that wrote the file names its pattern in its summary (DIR/ or
    // DIR/frames/)
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
  }
  const int expected = static_cast<int>(knit.control_points.cols());
  bool same =
      static_cast<int>(f.yarn_cp_counts.size()) == knit.num_yarns() && f.num_cp() == expected;
  for (int y = 0; same && y < knit.num_yarns(); ++y)
    same = static_cast<int>(f.yarn_cp_counts[y]) == knit.yarn_segments[y] + 3;
  if (!same)
    throw std::invalid_argument(
        "--resume " + path + ": it holds " + std::to_string(f.yarn_cp_counts.size()) +
        " yarn(s) and " + std::to_string(f.num_cp()) + " control points, but " + pattern +
        " at this size has " + std::to_string(knit.num_yarns()) + " yarn(s) and " +
        std::to_string(expected) + " (give the --rows, --cols and options of the first run)");
  for (size_t i = 0; i < f.stitch.size(); ++i)
    if (f.stitch[i].row != knit.stitch[i].row || f.stitch[i].col != knit.stitch[i].col)
      throw std::invalid_argument("--resume " + path + ": segment " + std::to_string(i) +
                                  " belongs to stitch (" + std::to_string(f.stitch[i].row) + ", " +
                                  std::to_string(f.stitch[i].col) + "), but to (" +
                                  std::to_string(knit.stitch[i].row) + ", " +
                                  std::to_string(knit.stitch[i].col) + ") in " + pattern);
  return f.state;
}

KnitRelaxSettings relax_settings(const RelaxKnitOptions& o) {
  KnitRelaxSettings s;
  s.fire = o.fire;
  s.params = o.params;
  s.ke_per_length = o.run.ke_per_length;
  s.force_residual = o.run.force_residual;
  s.check_every = o.run.check_every;
  s.contact_reuse_widen = o.run.contact_reuse_widen;
  s.contact_reuse_widen_residual = o.run.contact_reuse_widen_residual;
  return s;
}

void apply_relax_settings(const KnitRelaxSettings& s, RelaxKnitOptions& o) {
  o.fire = s.fire;
  for (const std::string& name : relax_setting_params()) {
    const ParamDecl& d = param_decl(name);
    d.set(o.params, d.get(s.params));
  }
  o.run.ke_per_length = s.ke_per_length;
  o.run.force_residual = s.force_residual;
  o.run.check_every = s.check_every;
  o.run.contact_reuse_widen = s.contact_reuse_widen;
  o.run.contact_reuse_widen_residual = s.contact_reuse_widen_residual;
}

KnitRelaxation setup_knit_relaxation(const std::string& pattern_name, const RelaxKnitOptions& o) {
  validate_params(o.params);
  validate_relax_options(o.run, o.params.solver);
  check_knit_relaxation(o.knit, o.shrink, o.params);
  check_knitout_size(pattern_name, o.knit);
  KnitRelaxation r;
  r.knit = generate_knit(load_pattern(pattern_name), o.knit);
  Params params = o.params;
  if (o.fire) params.material.k_global = 0;
  Model model = build_knit_model(r.knit, params, o.shrink, o.glue_close_time);
  model.knit = KnitInfo{pattern_name,
                        o.knit.rows,
                        o.knit.cols,
                        o.knit.in_the_round,
                        o.knit.segments_per_stitch,
                        o.knit.stitch_size_cm,
                        o.shrink,
                        o.knit.bind_off,
                        o.knit.cast_on,
                        relax_settings(o)};
  r.state = o.resume ? *o.resume : generated_state(r.knit);
  if (r.state.q.size() != model.num_dof() || r.state.v.size() != model.num_dof())
    throw std::invalid_argument("the state to resume from does not match the knit's size");
  r.sim = std::make_unique<Simulator>(std::move(model));
  if (o.fire) {
    auto fire = std::make_unique<FireFilter>();
    r.fire = fire.get();
    r.sim->add_filter(std::move(fire));
  } else
    r.sim->add_filter(std::make_unique<NonRigidDampingFilter>(
        r.sim->model(), o.params.material.alpha_small, o.params.material.alpha_large,
        o.knit.in_the_round));
  return r;
}

RelaxResult relax_knit(const std::string& pattern_name, const RelaxKnitOptions& o) {
  // everything is validated before anything is written
  KnitRelaxation setup = setup_knit_relaxation(pattern_name, o);
  const GeneratedKnit& knit = setup.knit;
  Simulator& sim = *setup.sim;
  const Model& model = sim.model();
  RelaxResult result{model, setup.state, {}};
  const std::string& out = o.run.out_dir;
  check_start(sim, result.state);
  RunDirectory held;  // locked until the relaxed state is beside the final one
  if (!out.empty())
    held = o.run.continue_in_place ? continue_run_directory(out)
                                   : prepare_run_directory(out, o.run.overwrite);
  if (!out.empty() && !o.run.continue_in_place) {
    write_state_file((fs::path(out) / "initial.kstate").string(),
                     make_state_file(model, result.state));
  }
  const FabricShape initial = measure_fabric(model, generated_state(knit).q);

  RelaxOptions run = o.run;
  if (o.fire && run.force_residual == 0) run.force_residual = RELAX_FIRE_RESIDUAL;
  // a step halved (max_step_halvings) doubles again after 20 good ones: an oscillation a
  // too-long step grows before it fails is an uphill motion, which FIRE stops at once
  if (o.fire && run.halving_calm_steps == 0) run.halving_calm_steps = 20;
  nlohmann::json extra = {{"pattern", pattern_name},
                          {"method", o.fire ? "fire" : "damped_dynamics"},
                          {"rows", o.knit.rows},
                          {"cols", o.knit.cols},
                          {"in_the_round", o.knit.in_the_round},
                          {"segments_per_stitch", o.knit.segments_per_stitch},
                          {"shrink", o.shrink},
                          {"bind_off", o.knit.bind_off},
                          {"cast_on", o.knit.cast_on},
                          {"contact_points", o.params.discretisation.contact_points},
                          {"k_global", model.params.material.k_global},
                          {"alpha_small", o.params.material.alpha_small},
                          {"alpha_large", o.params.material.alpha_large},
                          {"generated",
                           {{"stitch_width_cm", knit.stitch_width_cm},
                            {"row_height_cm", knit.row_height_cm},
                            {"loop_depth_cm", knit.loop_depth_cm},
                            {"loop_length_cm", knit.loop_length_cm},
                            {"min_distance_ratio", knit.min_distance_ratio},
                            {"shape", to_json(initial)}}}};
  if (o.fire) extra["alpha_small"] = extra["alpha_large"] = nullptr;  // no damping filter
  for (const auto& [k, v] : o.extra.items()) extra[k] = v;
  result.report = relax(sim, result.state, run, extra,
                        [&](Simulator&, const State& st, nlohmann::json& summary) {
                          const nlohmann::json shape = to_json(measure_fabric(model, st.q));
                          for (const auto& [k, v] : shape.items()) summary[k] = v;
                          if (setup.fire) summary["fire_restarts"] = setup.fire->restarts();
                        });
  copy_relaxed(out, result.report);
  return result;
}

RelaxResult relax_yarns(const std::string& path, const RelaxYarnsOptions& o) {
  check_shrink(o.shrink);
  Params params = o.params;
  params.material.radius = o.import.radius;
  validate_params(params);
  validate_relax_options(o.run, params.solver);
  ModelBuilder builder;
  for (const ImportedYarn& y : import_yarns(path, o.import)) builder.add_yarn(y.control_points);
  const Model model = builder.build(params, o.shrink);
  RelaxResult result{model, {}, {}};
  result.state.q = builder.positions();
  result.state.v = Eigen::VectorXd::Zero(result.state.q.size());
  const std::string& out = o.run.out_dir;
  Simulator sim(model);
  check_start(sim, result.state);
  RunDirectory held;
  if (!out.empty())
    held = o.run.continue_in_place ? continue_run_directory(out)
                                   : prepare_run_directory(out, o.run.overwrite);
  if (!out.empty() && !o.run.continue_in_place) {
    write_state_file((fs::path(out) / "initial.kstate").string(),
                     make_state_file(model, result.state));
  }
  nlohmann::json extra = {{"from", path},
                          {"shrink", o.shrink},
                          {"contact_points", params.discretisation.contact_points},
                          {"k_global", params.material.k_global}};
  for (const auto& [k, v] : o.extra.items()) extra[k] = v;
  result.report = relax(sim, result.state, o.run, extra);
  copy_relaxed(out, result.report);
  return result;
}

}  // namespace knit
