#include "knit/recipes/sheet_stretch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>

#include "knit/analysis/fabric_shape.hpp"
#include "knit/io/state_file.hpp"
#include "knit/run/interrupt.hpp"
#include "knit/sheet/embedding.hpp"
#include "knit/sheet/sheet_solver.hpp"
#include "knit/solver/simulator.hpp"
#include "knit/util/atomic_file.hpp"
#include "knit/util/run_dir.hpp"

namespace knit {

namespace fs = std::filesystem;

namespace {

// mean position of the segments whose stitch coordinate satisfies `pick`
template <class Pick>
Eigen::Vector3d segment_mean(const StateFile& file, const Eigen::VectorXd& q, Pick pick) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0, seg = 0;
  const std::vector<int> begin = file.yarn_cp_begin();
  for (size_t y = 0; y < file.yarn_cp_counts.size(); ++y)
    for (int i = 0; i + 3 < file.yarn_cp_counts[y]; ++i, ++seg) {
      if (!pick(file.stitch[seg])) continue;
      for (int j = 0; j < 4; ++j) sum += q.segment<3>(3 * (begin[y] + i + j));
      n += 4;
    }
  return n > 0 ? Eigen::Vector3d(sum / n) : sum;
}

void check_material(const sheet::SheetMaterial& m) {
  auto positive = [](double x, const char* name) {
    if (!(x > 0) || !std::isfinite(x) || x > 1e12)
      throw std::invalid_argument(std::string(name) + ": expected a stiffness in (0, 1e12], got " +
                                  short_number(x));
  };
  positive(m.k_stretch_u, "sheet k_stretch_u (course)");
  positive(m.k_stretch_v, "sheet k_stretch_v (wale)");
  positive(m.k_shear, "sheet k_shear");
  if (!(m.k_bend >= 0) || !std::isfinite(m.k_bend) || m.k_bend > 1e12)
    throw std::invalid_argument("sheet k_bend: expected [0, 1e12] erg, got " +
                                short_number(m.k_bend));
}

// the sheet's equilibrium with the moving clamp `strain` along the pull from where it
// started; `state` holds the previous solution (a warm start) and ends with this one
struct StaticSample {
  double force_fixed = 0, force_moving = 0, energy = 0;
  int iterations = 0, factorizations = 0, projected_iterations = 0;
  bool converged = false;
};

StaticSample solve_at(const KnitSheet& ks, const StretchGeometry& g,
                      const sheet::SheetMaterial& material, double strain,
                      sheet::SheetState& state) {
  const Eigen::VectorXd rest = ks.mesh.rest_positions();
  const Eigen::Vector3d shift = strain * g.separation * g.axis;
  for (int n : ks.fixed_nodes) state.positions.segment<3>(3 * n) = rest.segment<3>(3 * n);
  for (int n : ks.moving_nodes) state.positions.segment<3>(3 * n) = rest.segment<3>(3 * n) + shift;
  const std::vector<sheet::SheetConstraint> clamps = {{"fixed", ks.fixed_nodes, {0, 0, 0}},
                                                      {"moving", ks.moving_nodes, {0, 0, 0}}};
  sheet::StaticSettings settings;
  settings.gravity.setZero();
  settings.max_iterations = 2000;
  // the projected Newton iteration (the default): along the bias the sheet wrinkles, which
  // BW's Gauss–Newton matrix cannot see (docs/core.md)
  settings.hessian = sheet::Jacobians::PROJECTED;
  // converged when the free nodes' force is a billionth of the stiffest modulus times the
  // sample's size (dyn) or 1e-8 of where it started: round-off limits stiff sheets
  const double k_max = std::max({material.k_stretch_u, material.k_stretch_v, material.k_shear});
  settings.force_tolerance = 1e-9 * k_max * std::max(ks.width, ks.height);
  settings.relative_tolerance = 1e-8;
  const sheet::StaticReport r = sheet::solve_static(ks.mesh, material, clamps, settings, state);
  StaticSample s;
  s.force_fixed = -r.reactions[0].dot(g.axis);
  s.force_moving = r.reactions[1].dot(g.axis);
  s.energy = r.energy;
  s.iterations = r.iterations;
  s.factorizations = r.factorizations;
  s.projected_iterations = r.projected_iterations;
  s.converged = r.converged;
  return s;
}

nlohmann::json material_json(const sheet::SheetMaterial& m) {
  return {{"k_stretch_u_dyn_per_cm", m.k_stretch_u},
          {"k_stretch_v_dyn_per_cm", m.k_stretch_v},
          {"k_shear_dyn_per_cm", m.k_shear},
          {"k_bend_erg", m.k_bend}};
}

// the sheet's force per unit strain at `strain` (from rest)
double sheet_stiffness(const KnitSheet& ks, const StretchGeometry& g, const sheet::SheetMaterial& m,
                       double strain) {
  // a fit solves the sheet many times before anything is written: stop at a signal
  if (const int sig = interrupt_signal(); sig != 0)
    throw std::runtime_error(std::string("sheet fit: interrupted by ") +
                             interrupt_signal_name(sig) + ": nothing was written");
  sheet::SheetState state = sheet::rest_state(ks.mesh);
  const StaticSample s = solve_at(ks, g, m, strain, state);
  if (!s.converged)
    throw std::runtime_error("sheet fit: the sheet's statics did not converge at strain " +
                             short_number(strain));
  return s.force_moving / strain;
}

}  // namespace

KnitSheet make_knit_sheet(const StretchGeometry& g, double spacing) {
  if (!(spacing >= 0.05) || !(spacing <= 10) || !std::isfinite(spacing))
    throw std::invalid_argument("sheet node spacing: expected 0.05 to 10 cm, got " +
                                short_number(spacing));
  KnitSheet ks;
  const StateFile& f = g.file;
  int max_row = 0, max_col = 0;
  for (const StitchCoord& s : f.stitch) {
    max_row = std::max(max_row, s.row);
    max_col = std::max(max_col, s.col);
  }
  // course: from the first column to the last, in the plane; wale completes the frame,
  // the normal flipped so that it runs from the first row to the last
  Eigen::Vector3d n = g.normal;
  const Eigen::Vector3d course =
      segment_mean(f, g.q0, [&](const StitchCoord& s) { return s.col == max_col; }) -
      segment_mean(f, g.q0, [](const StitchCoord& s) { return s.col == 0; });
  Eigen::Vector3d u = course - course.dot(n) * n;
  if (!(u.norm() > 1e-9)) throw std::invalid_argument("sheet: the knit has no course direction");
  u.normalize();
  Eigen::Vector3d v = n.cross(u);
  const Eigen::Vector3d wale =
      segment_mean(f, g.q0, [&](const StitchCoord& s) { return s.row == max_row; }) -
      segment_mean(f, g.q0, [](const StitchCoord& s) { return s.row == 0; });
  if (wale.dot(v) < 0) {
    n = -n;
    v = -v;
  }
  ks.u_axis = u;
  ks.v_axis = v;
  ks.normal = n;
  const int ncp = static_cast<int>(g.q0.size() / 3);
  double umin = std::numeric_limits<double>::infinity(), umax = -umin, vmin = umin, vmax = -umin;
  for (int k = 0; k < ncp; ++k) {
    const Eigen::Vector3d d = g.q0.segment<3>(3 * k) - g.centroid;
    umin = std::min(umin, d.dot(u));
    umax = std::max(umax, d.dot(u));
    vmin = std::min(vmin, d.dot(v));
    vmax = std::max(vmax, d.dot(v));
  }
  ks.width = umax - umin;
  ks.height = vmax - vmin;
  const int nu = std::max(2, static_cast<int>(std::lround(ks.width / spacing)) + 1);
  const int nv = std::max(2, static_cast<int>(std::lround(ks.height / spacing)) + 1);
  if (static_cast<double>(nu) * nv > 2e6)
    throw std::invalid_argument("sheet node spacing " + short_number(spacing) +
                                " cm: " + std::to_string(nu) + "×" + std::to_string(nv) +
                                " nodes are too many (at most 2 million)");
  const Eigen::Vector3d origin = g.centroid + umin * u + vmin * v;
  ks.mesh = sheet::make_rectangle(origin, u, v, ks.width, ks.height, nu, nv);
  ks.embedded = g.q0.reshaped(3, ncp);

  // each clamp holds the nodes of a band (along u for a course pull, v for a wale pull,
  // both for bias) from the sample's edge to as far beyond the clamp's centre as its held
  // control points reach outside it: centred on the centre, as the yarn clamp's pull is
  // (the loops of neighbouring rows overlap, so the held points' own extent would reach
  // far into the free part)
  struct Band {
    double lo, hi, centre;
  };
  auto band = [&](const Clamp& c, const Eigen::Vector3d& axis) {
    Band b{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
           (c.centre - origin).dot(axis)};
    for (int k : c.control_points) {
      const double x = (g.q0.segment<3>(3 * k) - origin).dot(axis);
      b.lo = std::min(b.lo, x);
      b.hi = std::max(b.hi, x);
    }
    return b;
  };
  const Band fu = band(g.fixed, u), fv = band(g.fixed, v), mu = band(g.moving, u),
             mv = band(g.moving, v);
  // which coordinates a clamp spans: the one(s) along which the clamps are apart
  const double du = std::abs(mu.centre - fu.centre), dv = std::abs(mv.centre - fv.centre);
  const bool use_u = du > 0.25 * std::max(du, dv), use_v = dv > 0.25 * std::max(du, dv);
  // the band's inner edge: the low clamp's reaches 2c − lo, the high clamp's 2c − hi
  auto inner = [](const Band& b, bool low) {
    return low ? 2 * b.centre - b.lo : 2 * b.centre - b.hi;
  };
  const bool fixed_low_u = fu.centre < mu.centre, fixed_low_v = fv.centre < mv.centre;
  const double tol = 1e-9 * std::max(ks.width, ks.height);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double x = i * ks.width / (nu - 1), y = j * ks.height / (nv - 1);
      auto held = [&](const Band& bu, const Band& bv, bool low_u, bool low_v) {
        const double eu = inner(bu, low_u), ev = inner(bv, low_v);
        const bool ok_u = !use_u || (low_u ? x <= eu + tol : x >= eu - tol);
        const bool ok_v = !use_v || (low_v ? y <= ev + tol : y >= ev - tol);
        return ok_u && ok_v;
      };
      const int node = sheet::grid_node(ks.mesh, i, j);
      if (held(fu, fv, fixed_low_u, fixed_low_v))
        ks.fixed_nodes.push_back(node);
      else if (held(mu, mv, !fixed_low_u, !fixed_low_v))
        ks.moving_nodes.push_back(node);
    }
  if (ks.fixed_nodes.empty() || ks.moving_nodes.empty() ||
      ks.fixed_nodes.size() + ks.moving_nodes.size() >= static_cast<size_t>(nu) * nv)
    throw std::invalid_argument("sheet: the clamps hold no nodes or all of them (node spacing " +
                                short_number(spacing) + " cm)");
  return ks;
}

StretchResult stretch_sheet(const std::string& kstate_path, const SheetStretchOptions& so) {
  const StretchOptions& o = so.stretch;
  validate_stretch_options(o);
  check_material(so.material);
  const StretchGeometry g = stretch_geometry(kstate_path, o);
  const KnitSheet ks = make_knit_sheet(g, so.node_spacing);
  const auto t0 = std::chrono::steady_clock::now();
  const sheet::SheetEmbedding emb = sheet::embed_points(ks.mesh, ks.embedded);
  RunDirectory held;  // locked until its last output is written
  if (!o.out_dir.empty()) {
    held = prepare_run_directory(o.out_dir, o.overwrite);
    if (o.write_frames) {
      fs::create_directories(fs::path(o.out_dir) / "frames");
      claim_run_output((fs::path(o.out_dir) / "frames").string());
    }
  }

  // the samples' strains: out to the target, then back and forth for the cycles
  std::vector<double> strains = {0.0};
  const int per_pull = std::max(1, static_cast<int>(std::lround(o.to_strain / sample_strain(o))));
  for (int c = 0; c <= o.cycles; ++c)
    for (int k = 1; k <= per_pull; ++k) {
      const double e = o.to_strain * k / per_pull;
      strains.push_back(c % 2 == 0 ? e : o.to_strain - e);
    }

  StretchResult result;
  result.initial_separation = g.separation;
  result.axis = g.axis;
  result.speed = o.speed;
  sheet::SheetState state = sheet::rest_state(ks.mesh);
  int newton = 0, failed = 0, factorizations = 0, projected_iterations = 0;
  StateFile frame = g.file;
  double path = 0;  // strain travelled by the moving clamp so far
  int signal = 0;   // a SIGINT/SIGTERM ends the pull after its sample, with what it has
  for (size_t i = 0; i < strains.size(); ++i) {
    if (i > 0 && (signal = interrupt_signal()) != 0) break;
    const double e = strains[i];
    StaticSample st;
    st.converged = true;
    if (i > 0) st = solve_at(ks, g, so.material, e, state);
    newton += st.iterations;
    factorizations += st.factorizations;
    projected_iterations += st.projected_iterations;
    if (!st.converged) ++failed;
    const Eigen::Matrix3Xd yarn = sheet::deform(ks.mesh, emb, state.positions);
    const Eigen::VectorXd q = yarn.reshaped();
    StretchSample s;
    // nominal time: the yarn test's clamp speed over the path travelled so far
    if (i > 0) path += std::abs(strains[i] - strains[i - 1]);
    s.time = path * g.separation / o.speed;
    s.strain = e;
    s.force_fixed = st.force_fixed;
    s.force_moving = st.force_moving;
    s.width = g.width(q, e * g.separation);
    s.potential_energy = st.energy;
    s.kinetic_energy = 0;
    s.min_contact_distance = -1;
    s.edge_curl = measure_fabric(g.model, q).edge_curl;
    result.curve.push_back(s);
    if (!o.out_dir.empty() && o.write_frames) {
      frame.state.q = q;
      frame.state.v = Eigen::VectorXd::Zero(q.size());
      frame.state.time = s.time;
      char name[40];
      std::snprintf(name, sizeof(name), "state_%06zu.kstate", i);
      write_state_file((fs::path(o.out_dir) / "frames" / name).string(), frame);
    }
    if (o.progress)
      std::fprintf(stderr, "\rsheet: strain %.3f, force %.4g dyn, %d Newton iterations   ", e,
                   st.force_moving, st.iterations);
  }
  if (o.progress) std::fprintf(stderr, "\n");
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  const char* status = signal != 0 ? "interrupted" : failed == 0 ? "ok" : "not_converged";
  nlohmann::json summary = {{"status", status},
                            {"model", "sheet"},
                            {"direction", stretch_direction_name(o.direction)},
                            {"to_strain", o.to_strain},
                            {"cycles", o.cycles},
                            {"speed_cm_s", o.speed},
                            {"clamp_stitches", o.clamp_stitches},
                            {"from", kstate_path},
                            {"axis", {g.axis[0], g.axis[1], g.axis[2]}},
                            {"sim_time_s", result.curve.back().time},
                            {"wall_time_s", wall}};
  if (g.file.knit) {
    summary["pattern"] = g.file.knit->pattern;
    summary["rows"] = g.file.knit->rows;
    summary["cols"] = g.file.knit->cols;
  }
  summary["sheet"] = {{"nodes", ks.mesh.num_nodes()},
                      {"triangles", ks.mesh.triangles.size()},
                      {"node_spacing_cm", so.node_spacing},
                      {"course_cm", ks.width},
                      {"wale_cm", ks.height},
                      {"clamped_nodes", {ks.fixed_nodes.size(), ks.moving_nodes.size()}},
                      {"material", material_json(so.material)},
                      {"fit", so.fit},
                      {"newton_iterations", newton},
                      {"projected_iterations", projected_iterations},
                      {"factorizations", factorizations},
                      {"samples_not_converged", failed},
                      {"embedded_points", emb.size()}};
  summary["stretch"] = stretch_measures(result.curve, o.to_strain, g.separation);
  for (const auto& [k, v] : o.extra.items()) summary[k] = v;
  result.report.status = signal != 0   ? StepStatus::INTERRUPTED
                         : failed == 0 ? StepStatus::OK
                                       : StepStatus::NOT_CONVERGED;
  result.report.message =
      signal != 0 ? std::string("interrupted by ") + interrupt_signal_name(signal) + " at strain " +
                        short_number(result.curve.back().strain) + " (run it again)"
      : failed == 0 ? ""
                    : std::to_string(failed) + " samples did not reach equilibrium";
  if (signal != 0) summary["message"] = result.report.message;
  result.report.summary = summary;
  if (!o.out_dir.empty()) {
    const fs::path dir(o.out_dir);
    if (o.write_frames) write_state_file((dir / "final.kstate").string(), frame);
    write_file_atomic((dir / "summary.json").string(), summary.dump(2) + "\n");
    write_stretch_outputs(o, result.curve, "sheet, " + stretch_label(g.file, o.direction),
                          failed == 0 && signal == 0);
  }
  return result;
}

SheetFit fit_sheet_material(const std::string& kstate_path, const std::vector<std::string>& runs,
                            const SheetStretchOptions& base) {
  SheetFit fit;
  fit.material = base.material;
  check_material(fit.material);
  fit.report = nlohmann::json::object();
  // what each run says: direction → (stiffness, strain where it was measured, clamps)
  struct Target {
    std::string run;
    double stiffness = 0, strain = 0;
    int clamps = 2;
  };
  std::map<std::string, Target> targets;
  // the fields read below, where present, of the types a stretch run writes (value()
  // would throw the JSON library's own words at a summary.json from elsewhere)
  auto typed = [](const nlohmann::json& s) {
    for (const char* key : {"model", "protocol"})
      if (s.contains(key) && !s[key].is_string()) return false;
    for (const char* key : {"to_strain", "output_strain"})
      if (s.contains(key) && !s[key].is_number()) return false;
    return !s.contains("clamp_stitches") || s["clamp_stitches"].is_number_integer();
  };
  for (const std::string& run : runs) {
    const fs::path path = fs::path(run) / "summary.json";
    std::ifstream in(path);
    if (!in) throw std::invalid_argument("--fit " + run + ": no summary.json");
    const nlohmann::json s = nlohmann::json::parse(in, nullptr, false);
    if (!s.is_object() || !s.contains("direction") || !s["direction"].is_string() ||
        !s.contains("stretch") || !s["stretch"].is_object() || !typed(s))
      throw std::invalid_argument("--fit " + run + ": not a stretch run's summary");
    if (s.value("model", "yarn") == "sheet")
      throw std::invalid_argument("--fit " + run + ": a sheet run; fit to the yarn model's runs");
    const nlohmann::json& k = s["stretch"]["stiffness_small_strain"];
    if (!k.is_number()) {
      // the slope over the first tenth of a continuous pull needs 3 samples there
      const double to = s.value("to_strain", 1.0);
      const double step = s.value("output_strain", StretchOptions{}.output_strain);
      const double need = 30 * step;
      if (s.value("protocol", "continuous") == "continuous" && to < need * (1 - 1e-9))
        throw std::invalid_argument(
            "--fit " + run + ": the run measured no small-strain stiffness: it is the slope over " +
            "the first tenth of the pull, which needs 3 samples (one every " + short_number(step) +
            " strain), and this run pulled to " + short_number(to) + ": pull further (--to " +
            short_number(need) + " or more)");
      throw std::invalid_argument("--fit " + run +
                                  ": the run measured no small-strain stiffness (did it stop "
                                  "early? its summary's status says)");
    }
    if (!(k.get<double>() > 0))
      throw std::invalid_argument("--fit " + run + ": its small-strain stiffness is " +
                                  short_number(k.get<double>()) +
                                  " dyn per unit strain, not positive: nothing to fit a sheet to");
    Target t;
    t.run = run;
    t.stiffness = k.get<double>();
    t.strain = 0.05 * s.value("to_strain", 1.0);  // the middle of the first tenth
    t.clamps = s.value("clamp_stitches", 2);
    const std::string d = s["direction"].get<std::string>();
    parse_stretch_direction(d);
    if (targets.count(d)) throw std::invalid_argument("--fit: two " + d + " runs");
    targets[d] = t;
  }
  auto setup = [&](const std::string& d, const Target& t) {
    StretchOptions o = base.stretch;
    o.direction = parse_stretch_direction(d);
    o.clamp_stitches = t.clamps;
    const StretchGeometry g = stretch_geometry(kstate_path, o);
    return std::pair<StretchGeometry, KnitSheet>(g, make_knit_sheet(g, base.node_spacing));
  };
  // course and wale: a strip without Poisson coupling carries k_stretch in proportion
  // (a second pass corrects what shear near the clamps adds)
  for (const char* d : {"course", "wale"}) {
    if (!targets.count(d)) continue;
    const Target& t = targets[d];
    const auto [g, ks] = setup(d, t);
    double& k = std::string(d) == "course" ? fit.material.k_stretch_u : fit.material.k_stretch_v;
    for (int pass = 0; pass < 4; ++pass) {
      const double s = sheet_stiffness(ks, g, fit.material, t.strain);
      k *= t.stiffness / s;
      if (std::abs(s / t.stiffness - 1) < 1e-3) break;
    }
    fit.report[d] = {{"run", t.run},
                     {"yarn_stiffness", t.stiffness},
                     {"at_strain", t.strain},
                     {"sheet_stiffness", sheet_stiffness(ks, g, fit.material, t.strain)}};
  }
  // bias: bisection on log k_shear (the bias stiffness grows with it)
  if (targets.count("bias")) {
    const Target& t = targets["bias"];
    // (not a structured binding: the lambda below uses both, which clang before 16 refuses)
    const std::pair<StretchGeometry, KnitSheet> setup_bias = setup("bias", t);
    const StretchGeometry& g = setup_bias.first;
    const KnitSheet& ks = setup_bias.second;
    sheet::SheetMaterial m = fit.material;
    auto stiffness = [&](double ks_) {
      m.k_shear = ks_;
      return sheet_stiffness(ks, g, m, t.strain);
    };
    // bracket a decade at a time from shear as stiff as stretch, downward or upward: a
    // sheet far softer in shear than in stretch converges slowly (Gauss–Newton), and at a
    // ten-thousandth of the stretch stiffness a 42×32 one did not converge at all, so the
    // soft end is visited only when the answer lies there
    const double floor_k = 1e-4 * std::min(m.k_stretch_u, m.k_stretch_v),
                 ceiling_k = 1e2 * std::max(m.k_stretch_u, m.k_stretch_v);
    double lo = std::max(m.k_stretch_u, m.k_stretch_v), hi = lo;
    bool below = false, above = false;
    if (stiffness(hi) >= t.stiffness) {
      for (;;) {  // downward until [lo, hi] brackets it
        if (lo / 10 < floor_k) {
          below = true;
          break;
        }
        hi = lo;
        lo /= 10;
        if (stiffness(lo) < t.stiffness) break;
      }
    } else {
      for (;;) {  // upward
        if (hi * 10 > ceiling_k) {
          above = true;
          break;
        }
        lo = hi;
        hi *= 10;
        if (stiffness(hi) >= t.stiffness) break;
      }
    }
    nlohmann::json note;
    if (below) {
      note = "the yarn model's bias stiffness is below the sheet's with almost no shear stiffness";
      m.k_shear = lo;
    } else if (above) {
      m.k_shear = hi;
      note = "the yarn model's bias stiffness is above the sheet's with the stiffest shear tried";
    } else {
      for (int i = 0; i < 60 && hi / lo > 1 + 1e-4; ++i) {
        const double mid = std::sqrt(lo * hi);
        (stiffness(mid) < t.stiffness ? lo : hi) = mid;
      }
      m.k_shear = std::sqrt(lo * hi);
    }
    fit.material.k_shear = m.k_shear;
    fit.report["bias"] = {{"run", t.run},
                          {"yarn_stiffness", t.stiffness},
                          {"at_strain", t.strain},
                          {"sheet_stiffness", sheet_stiffness(ks, g, fit.material, t.strain)}};
    if (!note.is_null()) fit.report["bias"]["note"] = note;
  }
  fit.report["material"] = material_json(fit.material);
  return fit;
}

}  // namespace knit
