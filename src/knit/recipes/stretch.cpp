#include "knit/recipes/stretch.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "knit/analysis/fabric_shape.hpp"
#include "knit/filters/hold_relax.hpp"
#include "knit/io/csv.hpp"
#include "knit/io/state_file.hpp"
#include "knit/io/states.hpp"
#include "knit/recipes/simulate_scene.hpp"
#include "knit/scene/scene.hpp"
#include "knit/util/atomic_file.hpp"
#include "knit/util/run_dir.hpp"

namespace knit {

namespace fs = std::filesystem;

StretchDirection parse_stretch_direction(const std::string& name) {
  if (name == "course") return StretchDirection::COURSE;
  if (name == "wale") return StretchDirection::WALE;
  if (name == "bias") return StretchDirection::BIAS;
  throw std::invalid_argument("--direction: expected course, wale or bias, got \"" + name + "\"");
}

const char* stretch_direction_name(StretchDirection d) {
  switch (d) {
    case StretchDirection::COURSE:
      return "course";
    case StretchDirection::WALE:
      return "wale";
    case StretchDirection::BIAS:
      return "bias";
  }
  return "course";
}

Params stretch_params() {
  Params p = Params::simulation();
  p.gravity.setZero();
  return p;
}

namespace {

// the two clamps as scene JSON: "fixed" at the start of the rows/columns, "moving" at
// their end, with the moving one's keyframes
nlohmann::json clamps_json(StretchDirection d, int k, const nlohmann::json& keyframes) {
  const nlohmann::json first = {0, k - 1}, last = {-k, -1};
  nlohmann::json fixed = {{"name", "fixed"}}, moving = {{"name", "moving"}};
  if (d == StretchDirection::COURSE) {
    fixed["cols"] = first;
    moving["cols"] = last;
  } else if (d == StretchDirection::WALE) {
    fixed["rows"] = first;
    moving["rows"] = last;
  } else {
    fixed["rows"] = first;
    fixed["cols"] = first;
    moving["rows"] = last;
    moving["cols"] = last;
  }
  if (!keyframes.empty()) moving["keyframes"] = keyframes;
  return nlohmann::json::array({fixed, moving});
}

Scene stretch_scene(const std::string& path, const StretchOptions& o,
                    const nlohmann::json& keyframes) {
  // the knit's state path is read relative to the scene's own path: give it absolute
  const std::string state = fs::absolute(path).string();
  const nlohmann::json doc = {{"knits", nlohmann::json::array({{{"state", state}}})},
                              {"clamps", clamps_json(o.direction, o.clamp_stitches, keyframes)}};
  return parse_scene(doc, path, o.params);
}

// least-squares slope of y against x over the samples with x in [lo, hi]; NaN if < 3
// (< 2 with `two`)
double slope(const std::vector<StretchSample>& c, size_t n, double lo, double hi,
             bool two = false) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int m = 0;
  for (size_t i = 0; i < n; ++i) {
    const double x = c[i].strain, y = c[i].force_moving;
    if (x < lo || x > hi) continue;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++m;
  }
  if (m < (two ? 2 : 3)) return std::numeric_limits<double>::quiet_NaN();
  const double den = m * sxx - sx * sx;
  return den > 0 ? (m * sxy - sx * sy) / den : std::numeric_limits<double>::quiet_NaN();
}

nlohmann::json number_or_null(double x) {
  return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
}

}  // namespace

nlohmann::json stretch_measures(const std::vector<StretchSample>& all, double to,
                                double initial_separation, double hold_strain) {
  const bool held = hold_strain > 0;
  std::vector<StretchSample> curve;
  for (const StretchSample& s : all)
    if (!held || s.equilibrium) curve.push_back(s);
  nlohmann::json m;
  m["initial_separation_cm"] = initial_separation;
  // the first pull: samples up to the first one at the target strain
  size_t n = curve.size();
  for (size_t i = 0; i < curve.size(); ++i)
    if (curve[i].strain >= to * (1 - 1e-9)) {
      n = i + 1;
      break;
    }
  const double window = std::max(0.1 * to, 2 * hold_strain * (1 + 1e-9));
  // a continuous pull's small-strain slope leaves out the rest sample at strain 0: a
  // clamp that starts moving at speed meets the damping's drag at once, a jump that is
  // not stiffness; a held curve's first sample ends a hold like the others
  const double k0 = slope(curve, n, held ? -1e-12 : 1e-12, window, held);
  m["stiffness_small_strain"] = number_or_null(k0);
  // the end the pull reached: its target strain, or where it stopped (a load limit, a
  // failed step)
  const double end = n > 0 ? std::min(to, curve[n - 1].strain) : to;
  m["stiffness_end"] = number_or_null(slope(curve, n, end - window, end, held));
  double stiffening = std::numeric_limits<double>::quiet_NaN();
  if (std::isfinite(k0) && k0 > 0)
    for (double e = window; e + window <= to * (1 + 1e-9); e += 0.5 * window)
      if (slope(curve, n, e, e + window, held) >= 3 * k0) {
        stiffening = e;
        break;
      }
  m["stiffening_strain"] = number_or_null(stiffening);
  double work = 0, max_force = 0;
  for (size_t i = 1; i < curve.size(); ++i) {
    const double dx = (curve[i].strain - curve[i - 1].strain) * initial_separation;
    work += 0.5 * (curve[i].force_moving + curve[i - 1].force_moving) * dx;
  }
  for (const StretchSample& s : curve) max_force = std::max(max_force, s.force_moving);
  m["work_erg"] = work;
  m["max_force_dyn"] = max_force;
  if (!curve.empty() && curve.front().width > 0)
    m["width_change"] = curve[n - 1].width / curve.front().width - 1;
  if (!curve.empty()) {
    m["edge_curl_start"] = curve.front().edge_curl;
    m["edge_curl_end"] = curve[n - 1].edge_curl;
  }
  return m;
}

namespace {
// a number as the shortest text that reads back as the same double: a pull resumed from
// its directory reads its curve so far back from stretch.csv, and its summary's measures
// (work, width change, edge curl) are then the uninterrupted pull's, bit for bit
std::string csv_number(double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}
}  // namespace

void write_stretch_csv(const std::vector<StretchSample>& curve, const std::string& path) {
  std::string o =
      "time_s,strain,force_fixed_dyn,force_moving_dyn,width_cm,potential_energy_erg,"
      "kinetic_energy_erg,min_contact_distance,edge_curl,force_residual,equilibrium\n";
  for (const StretchSample& s : curve) {
    for (double v : {s.time, s.strain, s.force_fixed, s.force_moving, s.width, s.potential_energy,
                     s.kinetic_energy, s.min_contact_distance, s.edge_curl,
                     std::isfinite(s.force_residual) ? s.force_residual : -1.0})
      o += csv_number(v) + ",";
    o += s.equilibrium ? "1\n" : "0\n";
  }
  write_file_atomic(path, o);
}

namespace {
// (stretch.csv's times read back exactly; written by earlier builds, to ten significant digits)
bool same_time(double a, double b) {
  return std::abs(a - b) <= 1e-8 * std::max(1.0, std::abs(b));
}
}  // namespace

std::vector<StretchSample> read_stretch_csv(const std::string& path) {
  const CsvTable t = read_csv(path);
  const int time = t.column("time_s", path), strain = t.column("strain", path),
            fixed = t.column("force_fixed_dyn", path), moving = t.column("force_moving_dyn", path),
            width = t.column("width_cm", path), pe = t.column("potential_energy_erg", path),
            ke = t.column("kinetic_energy_erg", path),
            contact = t.column("min_contact_distance", path), curl = t.column("edge_curl", path),
            residual = t.column("force_residual", path),
            equilibrium = t.column("equilibrium", path);
  std::vector<StretchSample> curve;
  for (const std::vector<double>& row : t.rows) {
    StretchSample s;
    s.time = row[time];
    s.strain = row[strain];
    s.force_fixed = row[fixed];
    s.force_moving = row[moving];
    s.width = row[width];
    s.potential_energy = row[pe];
    s.kinetic_energy = row[ke];
    s.min_contact_distance = row[contact];
    s.edge_curl = row[curl];
    s.force_residual = row[residual] < 0 ? std::numeric_limits<double>::quiet_NaN() : row[residual];
    s.equilibrium = row[equilibrium] > 0.5;
    curve.push_back(s);
  }
  return curve;
}

std::string stretch_resume_state(const std::string& out_dir) {
  const fs::path dir(out_dir), csv = dir / "stretch.csv";
  if (!fs::exists(csv))
    throw std::invalid_argument("--resume " + out_dir +
                                ": no stretch.csv there, so no curve to go on with (a run "
                                "writes it from its first sample; stretch it again)");
  const std::vector<StretchSample> curve = read_stretch_csv(csv.string());
  if (curve.empty()) throw std::invalid_argument("--resume " + out_dir + ": stretch.csv is empty");
  const double last = curve.back().time;
  auto has_row = [&](double t) {
    return std::any_of(curve.begin(), curve.end(),
                       [t](const StretchSample& s) { return same_time(s.time, t); });
  };
  std::ifstream in(dir / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in, nullptr, false);
  // an interrupt's final state, or the last checkpoint of a pull without frames killed
  // outright (RunOptions::checkpoint_every_s) where stretch.csv has its sample
  const std::string status = summary.is_object() ? summary.value("status", "") : "";
  const fs::path final_state = dir / "final.kstate";
  if (fs::exists(final_state) &&
      (status == "interrupted" ||
       (status == "running" && has_row(read_state_file(final_state.string()).state.time))))
    return final_state.string();
  std::vector<std::string> frames;
  if (fs::is_directory(dir / "frames"))
    for (const auto& e : fs::directory_iterator(dir / "frames"))
      if (e.path().extension() == ".kstate") frames.push_back(e.path().string());
  std::sort(frames.rbegin(), frames.rend());
  for (const std::string& f : frames) {
    const double t = read_state_file(f).state.time;
    if (t <= last + 1e-6 && has_row(t)) return f;
  }
  throw std::invalid_argument("--resume " + out_dir +
                              ": no frame there has a sample in stretch.csv (frames/ holds " +
                              std::to_string(frames.size()) + " states)");
}

double sample_strain(const StretchOptions& o) {
  return std::min(o.output_strain, o.to_strain);
}

void validate_stretch_options(const StretchOptions& o) {
  if (!(o.to_strain > 0) || !std::isfinite(o.to_strain) || o.to_strain > 10)
    throw std::invalid_argument("--to: expected a strain in (0, 10], got " +
                                short_number(o.to_strain));
  if (!(o.speed > 0) || !std::isfinite(o.speed) || o.speed > 1000)
    throw std::invalid_argument("--speed: expected (0, 1000] cm/s, got " + short_number(o.speed));
  if (o.cycles < 0 || o.cycles > 100)
    throw std::invalid_argument("--cycles: expected 0 to 100, got " + std::to_string(o.cycles));
  if (o.clamp_stitches < 1) throw std::invalid_argument("--clamp-stitches: expected at least 1");
  if (o.render && (o.render_width < 16 || o.render_height < 16 || o.render_width > 8192 ||
                   o.render_height > 8192))
    throw std::invalid_argument("render size: expected 16 to 8192 pixels each way");
  // a pull shorter than the sample spacing is sampled at its end (sample_strain)
  if (!(o.output_strain > 0) || !std::isfinite(o.output_strain) || o.output_strain > 10)
    throw std::invalid_argument(
        "output_strain (the strain between samples): expected (0, 10], got " +
        short_number(o.output_strain));
  if (!std::isfinite(o.hold_strain) || o.hold_strain < 0 || o.hold_strain > o.to_strain)
    throw std::invalid_argument("--hold: expected a strain step in (0, --to], got " +
                                short_number(o.hold_strain));
  if (o.hold_strain > 0 && (!(o.hold_time > 0) || !std::isfinite(o.hold_time) || o.hold_time > 100))
    throw std::invalid_argument("--hold-time: expected (0, 100] s, got " +
                                short_number(o.hold_time));
  if (!std::isfinite(o.max_force) || o.max_force < 0 || o.max_force > 1e12)
    throw std::invalid_argument("--max-force: expected [0, 1e12] dyn (0: no limit), got " +
                                short_number(o.max_force));
  validate_params(o.params);
}

StretchGeometry stretch_geometry(const std::string& kstate_path, const StretchOptions& o) {
  StretchGeometry g;
  g.file = read_state_file(kstate_path);
  if (g.file.stitch.empty())
    throw std::invalid_argument(kstate_path +
                                ": no stitch coordinates: stretch a knit written "
                                "by `knitsim relax`");
  int rows = 0, cols = 0;
  for (const StitchCoord& s : g.file.stitch) {
    rows = std::max(rows, s.row + 1);
    cols = std::max(cols, s.col + 1);
  }
  const int across = o.direction == StretchDirection::WALE     ? rows
                     : o.direction == StretchDirection::COURSE ? cols
                                                               : std::min(rows, cols);
  if (across < 2 * o.clamp_stitches + 1)
    throw std::invalid_argument(kstate_path + ": the sample has " + std::to_string(across) + " " +
                                (o.direction == StretchDirection::WALE ? "rows" : "columns") +
                                " along the pull; two clamps of " +
                                std::to_string(o.clamp_stitches) + " need at least " +
                                std::to_string(2 * o.clamp_stitches + 1));

  // the clamps' centres give the pull axis and the initial separation
  const Scene probe = stretch_scene(kstate_path, o, nlohmann::json::array());
  g.model = probe.model;
  g.fixed = probe.model.clamps[0];
  g.moving = probe.model.clamps[1];
  g.q0 = probe.state.q;
  g.radius = probe.model.params.material.radius;
  const Eigen::Vector3d c0 = g.fixed.centre, c1 = g.moving.centre;
  g.separation = (c1 - c0).norm();
  if (!(g.separation > 0)) throw std::invalid_argument(kstate_path + ": the two clamps coincide");
  g.axis = (c1 - c0) / g.separation;
  // across the pull, in the fabric: the sample's normal is its direction of least spread
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  const int ncp = probe.model.num_cp();
  for (int k = 0; k < ncp; ++k) mean += g.q0.segment<3>(3 * k);
  mean /= ncp;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int k = 0; k < ncp; ++k) {
    const Eigen::Vector3d d = g.q0.segment<3>(3 * k) - mean;
    cov += d * d.transpose();
  }
  g.centroid = mean;
  g.normal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  g.across = g.normal.cross(g.axis).normalized();
  return g;
}

double StretchGeometry::width(const Eigen::VectorXd& q, double moved) const {
  // the width across the pull of the band of control points around the middle (± half a cm)
  const double band = 0.5 * radius * 8;
  const double mid = 0.5 * (fixed.centre.dot(axis) + moving.centre.dot(axis) + moved);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int k = 0; k < static_cast<int>(q.size() / 3); ++k) {
    const Eigen::Vector3d p = q.segment<3>(3 * k);
    if (std::abs(p.dot(axis) - mid) > band) continue;
    lo = std::min(lo, p.dot(across));
    hi = std::max(hi, p.dot(across));
  }
  return hi >= lo ? hi - lo + 2 * radius : 0.0;
}

void write_stretch_outputs(const StretchOptions& o, const std::vector<StretchSample>& curve,
                           const std::string& label, bool ended) {
  const fs::path dir(o.out_dir);
  write_stretch_csv(curve, (dir / "stretch.csv").string());
  if (!o.figures) return;
  const nlohmann::json renders = o.figures(o, curve, label, ended);
  if (renders.is_null()) return;
  // the summary was written by the run: add where the pictures are
  const fs::path summary_path = dir / "summary.json";
  std::ifstream in(summary_path);
  nlohmann::json summary = nlohmann::json::parse(in);
  in.close();
  summary["renders"] = renders;
  write_file_atomic(summary_path.string(), summary.dump(2) + "\n");
}

std::string stretch_label(const StateFile& file, StretchDirection direction) {
  return std::string(file.knit ? file.knit->pattern + ", " : "") +
         stretch_direction_name(direction) +
         (file.knit && file.knit->bind_off ? ", bound off" : "") +
         (file.knit && file.knit->cast_on ? ", cast on" : "");
}

namespace {

// StretchOptions::resume: checks that the state and the curve so far belong to this pull,
// puts the state into the scene, the curve into the result and the run's totals so far
// into `totals`; returns the state's path
std::string resume_stretch(const StretchOptions& o, Scene& scene, bool held, StretchResult& result,
                           std::optional<RunTotals>& totals) {
  const std::string what = "--resume " + o.resume;
  if (held)
    throw std::invalid_argument(what +
                                ": a held pull (--hold) cannot be resumed (FIRE's state is not "
                                "in the frames); run it again");
  if (o.out_dir.empty())
    throw std::invalid_argument(what + ": give the run's directory (--out) to go on in");
  if (o.overwrite)
    throw std::invalid_argument(what + ": goes on with the run in " + o.out_dir +
                                "; --overwrite would erase it");
  std::error_code ec;
  const bool dir = fs::is_directory(o.resume, ec);
  if (dir && !fs::equivalent(o.resume, o.out_dir, ec))
    throw std::invalid_argument(what + ": a directory to resume must be the run's --out " +
                                o.out_dir);
  const std::string path = dir ? stretch_resume_state(o.out_dir) : o.resume;
  if (!resumes_in_place(path, o.out_dir))
    throw std::invalid_argument(what + ": not a state of the run in " + o.out_dir +
                                " (its final.kstate or frames/)");
  StateFile file = read_state_file(path);
  const State& state = file.state;
  if (state.q.size() != scene.state.q.size())
    throw std::invalid_argument(what + ": it holds " + std::to_string(state.q.size() / 3) +
                                " control points, the knit pulled has " +
                                std::to_string(scene.state.q.size() / 3));
  const double h = scene.model.params.solver.time_step;
  if (!(state.time < scene.duration - 0.5 * h))
    throw std::invalid_argument(what + ": the state is at t = " + short_number(state.time) +
                                " s, the end of the pull (" + short_number(scene.duration) +
                                " s): nothing is left to run");
  // the summary of an interrupted run says what it pulled
  std::ifstream in(fs::path(o.out_dir) / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in, nullptr, false);
  if (summary.is_object() && summary.contains("direction") && summary["direction"].is_string() &&
      summary["direction"] != stretch_direction_name(o.direction))
    throw std::invalid_argument(what + ": the run pulled along the " +
                                summary["direction"].get<std::string>() + ", not the " +
                                stretch_direction_name(o.direction));
  if (summary.is_object() && summary.contains("cycles") && summary["cycles"].is_number() &&
      summary["cycles"] != o.cycles)
    throw std::invalid_argument(what + ": the run had --cycles " + summary["cycles"].dump());
  // the curve so far, up to the state's sample
  const fs::path csv = fs::path(o.out_dir) / "stretch.csv";
  if (!fs::exists(csv))
    throw std::invalid_argument(what + ": " + csv.string() +
                                " is missing, so the curve so far is lost; stretch it again");
  std::vector<StretchSample> curve = read_stretch_csv(csv.string());
  while (!curve.empty() && curve.back().time > state.time + 0.5 * h) curve.pop_back();
  if (curve.empty() || !same_time(curve.back().time, state.time))
    throw std::invalid_argument(what + ": " + csv.string() +
                                " has no sample at its time (t = " + short_number(state.time) +
                                " s); resume from the run's directory "
                                "to take the latest state that has one");
  // the same pull: the moving clamp must be where the sample says it was
  const Clamp& moving = scene.model.clamps[1];
  const double strain =
      moving.pose(state.time).translation.dot(result.axis) / result.initial_separation;
  if (std::abs(strain - curve.back().strain) > 1e-6 * std::max(1.0, std::abs(strain)))
    throw std::invalid_argument(
        what + ": at t = " + short_number(state.time) + " s the run was at strain " +
        short_number(curve.back().strain) + ", this pull would be at " + short_number(strain) +
        ": resume with the run's own knit, --direction, --to, --speed and --cycles");
  scene.state = state;
  result.curve = std::move(curve);
  totals = std::move(file.run);
  return path;
}

}  // namespace

std::vector<std::string> stretch_caveats(const StretchOptions& o) {
  std::vector<std::string> caveats;
  const double h = o.params.solver.time_step;
  // measured on a 7×6 stockinette pulled along the course at 5 cm/s, μ = 0.3, damping
  // filter off (README, "Speed II"): the explicit step's curve is reproduced within 3 % at
  // h = 1/11800 s, but not at the steps imex-contact is for (at any speed, before the
  // length constraints joined the solve: 30 % harder at 2e-4 s and 2.1× at 4e-4 s at
  // strain 0.2; with the length constraints in the solve, 2 % and 15 % there, 13 % and
  // 52 % at 0.3; with contact's transverse stiffness mirrored into the solve, which resists
  // sliding within a step, 3 % and 30 % at 0.2, 17 % and 79 % at 0.3)
  if (o.params.solver.integrator == Integrator::IMEX_CONTACT &&
      o.params.material.yarn_friction > 0 && h > 1e-4) {
    std::ostringstream step;
    step << h;
    caveats.push_back(
        "imex-contact with yarn friction does not reproduce the explicit step's force curve at "
        "h = " +
        step.str() +
        " s: on a 7x6 stockinette it pulled 17 % harder at "
        "h = 2e-4 s and 79 % at 4e-4 s (strain 0.3); use "
        "--integrator imex (within 5 % up to 4e-4 s) for stretch curves");
  }
  return caveats;
}

StretchResult stretch_knit(const std::string& kstate_path, const StretchOptions& opts) {
  // everything is validated before anything is written
  validate_stretch_options(opts);
  StretchOptions o = opts;
  const bool held = o.hold_strain > 0, fire = held && !o.hold_damped;
  if (fire) o.params.material.k_global = 0;  // a drag: zero at rest, it only slows FIRE
  const StretchGeometry g = stretch_geometry(kstate_path, o);
  StretchResult result;
  result.initial_separation = g.separation;
  result.axis = g.axis;
  const Eigen::Vector3d axis = g.axis;
  const double h = o.params.solver.time_step;

  // the moving clamp's keyframes (translation along the axis, cm)
  nlohmann::json keyframes = nlohmann::json::array({{{"time", 0.0}}});
  auto keyframe = [&](double time, double moved) {
    const Eigen::Vector3d t = moved * axis;
    keyframes.push_back({{"time", time}, {"translate", {t[0], t[1], t[2]}}});
  };
  const double stroke = o.to_strain * result.initial_separation;
  long long steps = 0;         // of the whole run
  long long output_every = 0;  // steps between samples
  long long hold_steps = 0;
  std::vector<std::pair<double, double>> holds;
  if (!held) {
    // out to the target strain, then back and forth, each pull a whole number of steps
    // (a partial last step would move the clamp slower and show as a dip)
    const long long pull_steps = std::max(1LL, std::llround(stroke / (o.speed * h)));
    const double pull_time = static_cast<double>(pull_steps) * h;
    result.speed = stroke / pull_time;
    for (int k = 1; k <= 1 + o.cycles; ++k) keyframe(k * pull_time, k % 2 == 1 ? stroke : 0.0);
    steps = (1 + o.cycles) * pull_steps;
    output_every =
        std::max(1LL, std::llround(sample_strain(o) * result.initial_separation / (o.speed * h)));
  } else {
    // a hold at strain 0, then per increment a move of move_steps and a hold of
    // hold_steps: every (move + hold) steps ends at rest, and is sampled
    const int increments = static_cast<int>(std::ceil(o.to_strain / o.hold_strain - 1e-9));
    const double inc = stroke / increments;
    const long long move_steps = std::max(1LL, std::llround(inc / (o.speed * h)));
    hold_steps = std::max(1LL, std::llround(o.hold_time / h));
    result.speed = inc / (static_cast<double>(move_steps) * h);
    const long long cycle = move_steps + hold_steps;
    const double T = static_cast<double>(cycle) * h;
    holds.emplace_back(0.0, T);
    double moved = 0;
    int n = 0;
    for (int k = 0; k <= o.cycles; ++k)
      for (int i = 1; i <= increments; ++i) {
        ++n;
        const double start = n * T, stop = start + static_cast<double>(move_steps) * h;
        keyframe(start, moved);
        moved = (k % 2 == 0 ? i : increments - i) * inc;
        keyframe(stop, moved);
        holds.emplace_back(stop, (n + 1) * T);
      }
    steps = static_cast<long long>(n + 1) * cycle;
    output_every = cycle;
  }
  Scene scene = stretch_scene(kstate_path, o, keyframes);
  scene.duration = static_cast<double>(steps) * h;
  scene.output_every = static_cast<int>(std::min<long long>(output_every, 1'000'000'000));
  const Clamp& moving = scene.model.clamps[1];
  std::optional<RunTotals> resumed_totals;
  const std::string resumed_from =
      o.resume.empty() ? "" : resume_stretch(o, scene, held, result, resumed_totals);
  RunDirectory locked;  // until the last plot and render are written
  if (!o.out_dir.empty())
    locked = resumed_from.empty() ? prepare_run_directory(o.out_dir, o.overwrite)
                                  : continue_run_directory(o.out_dir);

  const fs::path csv_path = fs::path(o.out_dir) / "stretch.csv";
  auto frame_of = [&](double time) {
    const long long step = std::llround(time / h);
    return (step + scene.output_every - 1) / scene.output_every;
  };
  auto sample = [&](const StepData& data, const State& state) {
    if (!result.curve.empty()) {
      // the resumed state's sample was read back with the curve
      if (state.time < result.curve.back().time + 0.5 * h) return;
      // a run resumed from a state between two samples (an interrupt's final.kstate) writes
      // its next frame over that state's: the sample goes with it
      if (frame_of(state.time) == frame_of(result.curve.back().time)) result.curve.pop_back();
    }
    StretchSample s;
    s.time = state.time;
    const double moved = moving.pose(state.time).translation.dot(axis);
    s.strain = moved / result.initial_separation;
    // a held curve: the static reactions, without the step's inertia and damping
    const ConstraintRecord* f = held ? data.static_constraint("fixed") : data.constraint("fixed");
    const ConstraintRecord* m = held ? data.static_constraint("moving") : data.constraint("moving");
    if (f) s.force_fixed = -f->force.dot(axis);
    if (m) s.force_moving = m->force.dot(axis);
    s.width = g.width(state.q, moved);
    s.potential_energy = data.potential_energy;
    s.kinetic_energy = data.kinetic_energy;
    s.min_contact_distance = data.contact.present && std::isfinite(data.contact.min_distance_ratio)
                                 ? data.contact.min_distance_ratio
                                 : -1;
    s.edge_curl = measure_fabric(scene.model, state.q).edge_curl;
    s.force_residual = data.force_residual;
    s.equilibrium = held && state.time > 0.5 * h;
    result.curve.push_back(s);
    // the curve so far is on disk at every sample: a killed run can be resumed
    if (!o.out_dir.empty()) write_stretch_csv(result.curve, csv_path.string());
  };

  std::unique_ptr<Simulator> sim;
  if (fire) {
    sim = std::make_unique<Simulator>(scene.model);
    sim->add_filter(
        std::make_unique<HoldRelaxFilter>(scene_filters(scene, sim->model()), std::move(holds)));
  } else {
    sim = make_scene_simulator(scene);
  }
  SimulateOptions so;
  so.out_dir = o.out_dir;
  so.progress = o.progress;
  so.write_frames = o.write_frames;
  so.check_crossings = o.check_crossings;
  so.continue_in_place = !resumed_from.empty();
  so.resumed_totals = resumed_totals;
  so.resume_command = o.resume_command;
  RunOptions run = scene_run_options(scene, so);
  run.on_output = sample;
  // the load limit, on the samples' forces (a step's own record also carries the jerk of
  // the clamp starting to move: 7× the force of the pull at its first step on a 5×6)
  nlohmann::json stopped;
  if (o.max_force > 0)
    run.stop_when = [&](const StepData&, const State&) {
      if (result.curve.empty()) return false;
      const StretchSample& s = result.curve.back();
      if (std::max(s.force_fixed, s.force_moving) <= o.max_force) return false;
      stopped = {{"reason", "max_force"},
                 {"max_force_dyn", o.max_force},
                 {"time_s", s.time},
                 {"strain", s.strain},
                 {"force_fixed_dyn", s.force_fixed},
                 {"force_moving_dyn", s.force_moving}};
      return true;
    };
  if (held) run.before_output = [](Simulator& s, const State& st) { s.force_residual(st); };
  run.extra = {{"model", "yarn"},
               {"direction", stretch_direction_name(o.direction)},
               {"to_strain", o.to_strain},
               {"cycles", o.cycles},
               {"speed_cm_s", result.speed},
               {"protocol", held ? "hold" : "continuous"},
               {"output_strain", o.output_strain},
               {"clamp_stitches", o.clamp_stitches},
               {"max_force_dyn", o.max_force > 0 ? nlohmann::json(o.max_force) : nlohmann::json()},
               {"from", kstate_path},
               {"axis", {axis[0], axis[1], axis[2]}}};
  if (held) {
    run.extra["hold_strain"] = o.to_strain / std::ceil(o.to_strain / o.hold_strain - 1e-9);
    run.extra["hold_time_s"] = static_cast<double>(hold_steps) * h;
    run.extra["hold_relax"] = fire ? "fire" : "damped";
  }
  if (!resumed_from.empty()) run.extra["resumed_from"] = resumed_from;
  if (const auto caveats = stretch_caveats(o); !caveats.empty()) run.extra["caveats"] = caveats;
  for (const auto& [k, v] : o.extra.items()) run.extra[k] = v;
  if (g.file.knit) {
    run.extra["pattern"] = g.file.knit->pattern;
    run.extra["bind_off"] = g.file.knit->bind_off;
    run.extra["cast_on"] = g.file.knit->cast_on;
    run.extra["rows"] = g.file.knit->rows;
    run.extra["cols"] = g.file.knit->cols;
  }
  run.on_finish = [&](Simulator&, const State&, nlohmann::json& summary) {
    summary["stretch"] =
        stretch_measures(result.curve, o.to_strain, result.initial_separation, o.hold_strain);
    if (!stopped.is_null()) summary["stretch"]["stopped"] = stopped;
    if (held) {
      // how near to rest the holds came: the force residual at their ends
      double worst = 0, sum = 0;
      int count = 0;
      for (const StretchSample& s : result.curve)
        if (s.equilibrium && std::isfinite(s.force_residual)) {
          worst = std::max(worst, s.force_residual);
          sum += s.force_residual;
          ++count;
        }
      summary["stretch"]["hold_residual_max"] = worst;
      summary["stretch"]["hold_residual_mean"] = count ? sum / count : 0.0;
    }
  };
  result.report = run_simulation(*sim, scene.state, run);

  if (!o.out_dir.empty())
    write_stretch_outputs(o, result.curve, stretch_label(g.file, o.direction),
                          result.report.status != StepStatus::INTERRUPTED);
  return result;
}

}  // namespace knit
