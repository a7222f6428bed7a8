// The stretch recipe on a small relaxed sample: the force rises with strain, the two clamps
// pull equally and oppositely, the outputs exist and parse, and bad options are refused
// before anything is written.
#include "knit/recipes/stretch.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "knit/io/state_file.hpp"
#include "knit/present/plot.hpp"
#include "knit/present/stretch_figures.hpp"
#include "knit/run/interrupt.hpp"
#include "knit/util/process.hpp"
#include "recipes/relaxed_sample.hpp"

namespace knit {
namespace {

namespace fs = std::filesystem;

// a 5×6 stockinette relaxed for 0.1 s by `knitsim relax` (shipped)
std::string relaxed_sample() {
  static const std::string path = relaxed_stockinette_sample(5, 6);
  return path;
}

TEST(Stretch, ForceRisesAndTheClampsBalance) {
  StretchOptions o;
  o.to_strain = 0.2;
  o.speed = 5;
  o.progress = false;
  o.out_dir = (fs::path(::testing::TempDir()) / "stretch_course").string();
  o.overwrite = true;
  o.render_width = 64;  // small pictures: the test checks that they are made
  o.render_height = 48;
  o.figures = write_stretch_figures;
  const StretchResult r = stretch_knit(relaxed_sample(), o);
  ASSERT_EQ(r.report.summary["status"], "ok") << r.report.summary.dump(2);
  ASSERT_GE(r.curve.size(), 15u);
  EXPECT_NEAR(r.curve.back().strain, 0.2, 1e-9);
  // the course axis is the knit's x
  EXPECT_GT(std::abs(r.axis.x()), 0.95) << r.axis.transpose();
  // tension builds up as the sample is pulled
  const StretchSample& mid = r.curve[r.curve.size() / 2];
  EXPECT_GT(mid.force_moving, 0.0);
  EXPECT_GT(r.curve.back().force_moving, r.curve[2].force_moving);
  // away from the start, the fixed clamp holds what the moving one pulls (the clamped
  // sample's momentum hardly changes): within 2 %
  for (const StretchSample& s : r.curve)
    if (s.strain >= 0.05 && s.strain < 0.2 - 1e-9)
      EXPECT_NEAR(s.force_fixed, s.force_moving, 0.02 * s.force_moving) << "strain " << s.strain;
  // the sample narrows across the pull
  EXPECT_LT(r.curve.back().width, r.curve.front().width);
  // the outputs: stretch.csv with the curve, the summary's measures
  const CsvTable t = read_csv(o.out_dir + "/stretch.csv");
  EXPECT_EQ(t.rows.size(), r.curve.size());
  EXPECT_NO_THROW(t.column("force_moving_dyn", "stretch.csv"));
  std::ifstream in(o.out_dir + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  for (const char* key :
       {"initial_separation_cm", "stiffness_small_strain", "stiffness_end", "stiffening_strain",
        "work_erg", "max_force_dyn", "width_change", "edge_curl_start", "edge_curl_end"})
    EXPECT_TRUE(s["stretch"].contains(key)) << key;
  EXPECT_EQ(s["direction"], "course");
  EXPECT_EQ(s["pattern"], "stockinette");
  EXPECT_GT(s["stretch"]["work_erg"].get<double>(), 0.0);
  if (!find_gnuplot().empty())
    for (const char* png : {"stretch_force.png", "stretch_width.png"})
      EXPECT_TRUE(fs::exists(o.out_dir + "/" + png)) << png;
  // renders at strain 0 and at the end (0.2 < 0.25), side by side, and a movie of the frames
  for (const char* png : {"stretch_renders.png", "renders/strain_0.png", "renders/strain_0.2.png"})
    EXPECT_TRUE(fs::exists(o.out_dir + "/" + png)) << png;
  EXPECT_EQ(s["renders"]["images"].size(), 2u) << s["renders"].dump();
  if (!find_executable("ffmpeg").empty())
    EXPECT_TRUE(fs::exists(o.out_dir + "/movie/animation.mp4"));
}

// The measures of a known curve: F = 50 + 100 ε after a jump at the start (a clamp that
// starts at speed meets the damping's drag at once), then F = 50 + 100 ε + 2000 (ε − 0.6)²
// beyond ε = 0.6, a stiffening; separation 10 cm.
TEST(Stretch, TheCurvesMeasuresAreTheKnownOnes) {
  std::vector<StretchSample> curve;
  for (int i = 0; i <= 100; ++i) {
    StretchSample s;
    s.strain = i / 100.0;
    const double e = s.strain;
    s.force_moving = i == 0 ? 0 : 50 + 100 * e + (e > 0.6 ? 2000 * (e - 0.6) * (e - 0.6) : 0);
    s.width = 5 - e;
    curve.push_back(s);
  }
  const nlohmann::json m = stretch_measures(curve, 1.0, 10.0);
  EXPECT_NEAR(m["stiffness_small_strain"].get<double>(), 100, 1e-9);  // the jump left out
  // the last tenth: slope of 100 + 4000 (ε − 0.6) averaged over [0.9, 1]
  EXPECT_NEAR(m["stiffness_end"].get<double>(), 100 + 4000 * 0.35, 1e-6);
  // 3 × 100 is first reached by a tenth-wide window starting where 4000 (ε₀ + 0.05 − 0.6) = 200
  EXPECT_NEAR(m["stiffening_strain"].get<double>(), 0.6, 0.051);
  // work: 10 cm × ∫ F dε by the trapezoid rule (the first interval from 0 to the jump)
  double work = 0;
  for (int i = 1; i <= 100; ++i)
    work += 0.5 * (curve[i].force_moving + curve[i - 1].force_moving) * 0.1;
  EXPECT_NEAR(m["work_erg"].get<double>(), work, 1e-9 * work);
  EXPECT_NEAR(m["width_change"].get<double>(), 4.0 / 5 - 1, 1e-12);
  // a pull that stopped at 0.8 (a load limit, a failed step): its end is there
  curve.resize(81);
  const nlohmann::json stopped = stretch_measures(curve, 1.0, 10.0);
  // the slope over [0.7, 0.8] lies between the curve's slopes at its two ends
  ASSERT_TRUE(stopped["stiffness_end"].is_number()) << stopped.dump();
  EXPECT_GT(stopped["stiffness_end"].get<double>(), 100 + 4000 * 0.1);
  EXPECT_LT(stopped["stiffness_end"].get<double>(), 100 + 4000 * 0.2);
  EXPECT_NEAR(stopped["width_change"].get<double>(), 4.2 / 5 - 1, 1e-12);
}

TEST(Stretch, WaleAndBiasPullAlongTheirAxes) {
  for (const char* d : {"wale", "bias"}) {
    StretchOptions o;
    o.direction = parse_stretch_direction(d);
    o.clamp_stitches = 1;
    o.to_strain = 0.05;
    o.progress = false;
    const StretchResult r = stretch_knit(relaxed_sample(), o);  // no out_dir: in memory
    ASSERT_EQ(r.report.summary["status"], "ok") << d;
    if (std::string(d) == "wale")
      EXPECT_GT(std::abs(r.axis.y()), 0.95) << r.axis.transpose();
    else
      EXPECT_GT(std::min(std::abs(r.axis.x()), std::abs(r.axis.y())), 0.4) << r.axis.transpose();
    EXPECT_GT(r.curve.back().force_moving, 0.0) << d;
  }
}

// with yarn friction asked for, the pull runs the friction filter: it acts on the clamped
// knit's contacts (most of which stick during a slow pull), and the summary says so
TEST(Stretch, YarnFrictionActsOnTheKnitsContacts) {
  StretchOptions o;
  o.to_strain = 0.05;
  o.speed = 1;
  o.progress = false;
  o.params.material.yarn_friction = 0.3;
  const StretchResult r = stretch_knit(relaxed_sample(), o);
  ASSERT_EQ(r.report.summary["status"], "ok");
  const auto& f = r.report.summary["yarn_friction"];
  EXPECT_GT(f["pairs_mean"].get<double>(), 50.0) << f.dump();
  EXPECT_GT(f["stuck_fraction"].get<double>(), 0.5) << f.dump();
  EXPECT_GT(f["work_erg"].get<double>(), 0.0) << f.dump();
  EXPECT_EQ(r.report.summary["params"]["material"]["yarn_friction"].get<double>(), 0.3);
}

// imex-contact with yarn friction pulls another curve than the explicit step at the steps
// it is for (docs/speed.md, Speed II): such a pull says so, in its summary; the others do not
TEST(Stretch, APullKnownToMisleadSaysSoInItsSummary) {
  StretchOptions o;
  o.to_strain = 0.01;
  o.progress = false;
  o.params.material.yarn_friction = 0.3;
  EXPECT_TRUE(stretch_caveats(o).empty());  // explicit
  o.params.solver.integrator = Integrator::IMEX;
  o.params.solver.time_step = 4e-4;
  EXPECT_TRUE(stretch_caveats(o).empty());
  o.params.solver.integrator = Integrator::IMEX_CONTACT;
  o.params.material.yarn_friction = 0;
  EXPECT_TRUE(stretch_caveats(o).empty());
  o.params.material.yarn_friction = 0.3;
  ASSERT_EQ(stretch_caveats(o).size(), 1u);
  EXPECT_NE(stretch_caveats(o)[0].find("--integrator imex"), std::string::npos);
  const StretchResult r = stretch_knit(relaxed_sample(), o);
  ASSERT_EQ(r.report.summary["status"], "ok");
  ASSERT_TRUE(r.report.summary.contains("caveats")) << r.report.summary.dump();
  EXPECT_EQ(r.report.summary["caveats"][0], stretch_caveats(o)[0]);
}

// A fast pull to strain 0.3 at a step of 3e-4 s, beyond the explicit step's limit.
StretchOptions unstable_pull() {
  StretchOptions o;
  o.to_strain = 0.3;
  o.speed = 50;
  o.progress = false;
  o.params.solver.time_step = 3e-4;
  return o;
}

// A pull that becomes unstable (unstable_pull) stops with its outputs up to the last strain
// it reached, renders included: the strains it passed and the last one, which the summary
// names.
TEST(Stretch, AnUnstablePullIsRenderedUpToWhereItStopped) {
  StretchOptions o = unstable_pull();
  o.out_dir = (fs::path(::testing::TempDir()) / "stretch_unstable").string();
  o.overwrite = true;
  o.render_width = 64;
  o.render_height = 48;
  o.figures = write_stretch_figures;
  const StretchResult r = stretch_knit(relaxed_sample(), o);
  ASSERT_EQ(r.report.summary["status"], "unstable") << r.report.summary.dump(2);
  ASSERT_GE(r.curve.size(), 2u);
  const double reached = r.curve.back().strain;
  EXPECT_GT(reached, 0.0);
  EXPECT_LT(reached, 0.3);
  std::ifstream in(o.out_dir + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  ASSERT_TRUE(s.contains("renders")) << s.dump(2);
  EXPECT_NEAR(s["renders"]["stopped_at_strain"].get<double>(), reached, 1e-12);
  // strain 0 and the last one reached (below 0.25 here), and nothing beyond it
  EXPECT_EQ(s["renders"]["images"].size(), 2u) << s["renders"].dump();
  for (const auto& [strain, png] : s["renders"]["images"].items()) {
    EXPECT_LE(std::stod(strain), reached * (1 + 1e-2)) << strain;  // named to 3 digits
    EXPECT_TRUE(fs::exists(o.out_dir + "/" + png.get<std::string>())) << png;
  }
  EXPECT_TRUE(fs::exists(o.out_dir + "/stretch_renders.png"));
  EXPECT_TRUE(fs::exists(o.out_dir + "/last_good.kstate"));
}

// Halving a failed step does not rescue a pull whose long steps were unstable for a while
// before one failed (here 3e-4 s, 3.5× the default step: the oscillation grows for
// a dozen steps first): the halved steps fail too, and the summary says how far it halved.
// (Where the step fails at a sound state it goes on: step_halving_test.cpp.)
TEST(Stretch, HalvingDoesNotRescueAPullLongUnstable) {
  StretchOptions o = unstable_pull();
  o.params.solver.max_step_halvings = 3;
  const StretchResult r = stretch_knit(relaxed_sample(), o);
  ASSERT_EQ(r.report.summary["status"], "unstable") << r.report.summary.dump(2);
  EXPECT_NE(r.report.message.find("halved 3 times, to 3.75e-05 s"), std::string::npos)
      << r.report.message;
  const auto& halvings = r.report.summary["step_halvings"];
  EXPECT_EQ(halvings["deepest"].get<int>(), 3) << halvings.dump();
  EXPECT_EQ(r.report.summary["params"]["solver"]["max_step_halvings"].get<int>(), 3);
}

// --from a relative path is read from the working directory (not from beside itself)
// A load limit ends the pull at the first sample where a clamp's force exceeds it: the
// curve up to there is the unlimited pull's, every earlier sample is within the limit, and
// the summary says where it stopped.
TEST(Stretch, ALoadLimitEndsThePullWhereTheForceFirstExceedsIt) {
  StretchOptions o;
  o.to_strain = 0.2;
  o.progress = false;
  const StretchResult whole = stretch_knit(relaxed_sample(), o);
  ASSERT_EQ(whole.report.summary["status"], "ok");
  double peak = 0;
  for (const StretchSample& s : whole.curve) peak = std::max(peak, s.force_moving);
  ASSERT_GT(peak, 0.0);
  o.max_force = 0.9 * peak;  // reached partway (the drag makes half the force at once)
  o.out_dir = (fs::path(::testing::TempDir()) / "stretch_limit").string();
  o.overwrite = true;
  o.render = false;
  const StretchResult r = stretch_knit(relaxed_sample(), o);
  ASSERT_EQ(r.report.summary["status"], "ok") << r.report.summary.dump(2);
  EXPECT_TRUE(r.report.summary["stopped_early"].get<bool>());
  const nlohmann::json& stop = r.report.summary["stretch"]["stopped"];
  ASSERT_TRUE(stop.is_object()) << r.report.summary["stretch"].dump(2);
  EXPECT_EQ(stop["reason"], "max_force");
  EXPECT_GT(std::max(stop["force_moving_dyn"].get<double>(), stop["force_fixed_dyn"].get<double>()),
            o.max_force);
  const double at = stop["strain"].get<double>();
  EXPECT_GT(at, 0.0);
  EXPECT_LT(at, 0.2);
  ASSERT_GE(r.curve.size(), 3u);
  EXPECT_NEAR(r.curve.back().strain, at, 1e-12);  // the stopping state is the last sample
  for (size_t k = 0; k + 1 < r.curve.size(); ++k) {
    EXPECT_LE(std::max(r.curve[k].force_moving, r.curve[k].force_fixed), o.max_force) << k;
    // the same pull as without the limit, sample for sample
    ASSERT_LT(k, whole.curve.size());
    EXPECT_NEAR(r.curve[k].force_moving, whole.curve[k].force_moving,
                1e-9 * std::abs(whole.curve[k].force_moving) + 1e-9)
        << k;
  }
  const CsvTable t = read_csv(o.out_dir + "/stretch.csv");
  EXPECT_EQ(t.rows.size(), r.curve.size());
  std::ifstream in(o.out_dir + "/summary.json");
  EXPECT_EQ(nlohmann::json::parse(in)["stretch"]["stopped"]["reason"], "max_force");
}

TEST(Stretch, ARelativePathIsReadFromTheWorkingDirectory) {
  const fs::path sample = relaxed_sample(), cwd = fs::current_path();
  fs::current_path(sample.parent_path());
  StretchOptions o;
  o.to_strain = 0.01;
  o.progress = false;
  std::string error;
  try {
    stretch_knit(sample.filename().string(), o);
  } catch (const std::exception& e) {
    error = e.what();
  }
  fs::current_path(cwd);
  EXPECT_EQ(error, "");
}

// The held protocol: one sample at the end of every hold (after a hold at strain
// 0 and after each step of 0.1), the forces the clamps' static reactions there. Newton's
// second law ties the two clamps together whether the sample has come to rest or not:
// with gravity off the internal forces cancel, so the clamps' net force is Σ m a over the
// control points, the accelerations that the force residual R measures (its mass-weighted
// RMS), hence |F_moving − F_fixed| ≤ M R along the pull (Cauchy–Schwarz).
TEST(Stretch, HeldClampsBalanceAsNewtonSays) {
  StretchOptions o;
  o.to_strain = 0.2;
  o.hold_strain = 0.1;
  o.hold_time = 0.05;
  o.progress = false;
  o.out_dir = (fs::path(::testing::TempDir()) / "stretch_hold").string();
  o.overwrite = true;
  o.render = false;
  const StretchResult r = stretch_knit(relaxed_sample(), o);
  ASSERT_EQ(r.report.summary["status"], "ok") << r.report.summary.dump(2);
  ASSERT_EQ(r.curve.size(), 4u);  // the start, and the holds at strain 0, 0.1, 0.2
  const double strains[] = {0, 0, 0.1, 0.2};
  const double mass = stretch_geometry(relaxed_sample(), o).model.mass.sum();
  const double cycle = r.curve[1].time;
  for (size_t i = 0; i < r.curve.size(); ++i) {
    const StretchSample& s = r.curve[i];
    SCOPED_TRACE("sample " + std::to_string(i));
    EXPECT_NEAR(s.strain, strains[i], 1e-9);
    EXPECT_EQ(s.equilibrium, i > 0);
    EXPECT_NEAR(s.time, static_cast<double>(i) * cycle, 1e-9);
    ASSERT_TRUE(std::isfinite(s.force_residual));
    EXPECT_LE(std::abs(s.force_moving - s.force_fixed), mass * s.force_residual * 1.01)
        << s.force_moving << " vs " << s.force_fixed << " dyn, R " << s.force_residual;
  }
  // each hold ends nearer to rest than the unrelaxed start
  for (size_t i = 1; i < r.curve.size(); ++i)
    EXPECT_LT(r.curve[i].force_residual, r.curve[0].force_residual);
  std::ifstream in(o.out_dir + "/summary.json");
  const auto summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["protocol"], "hold");
  EXPECT_NEAR(summary["hold_strain"].get<double>(), 0.1, 1e-12);
  EXPECT_TRUE(summary["stretch"].contains("hold_residual_max"));
  const CsvTable t = read_csv(o.out_dir + "/stretch.csv");
  EXPECT_EQ(t.rows.size(), 4u);
  EXPECT_EQ(t.rows[0][t.column("equilibrium", "stretch.csv")], 0.0);
  EXPECT_EQ(t.rows[3][t.column("equilibrium", "stretch.csv")], 1.0);
}

std::string file_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A short course pull of relaxed_sample() into TempDir()/NAME (written over), a sample every
// 0.01 of strain to 0.05.
StretchOptions small_pull(const std::string& name) {
  StretchOptions o;
  o.to_strain = 0.05;
  o.output_strain = 0.01;
  o.progress = false;
  o.render = false;
  o.overwrite = true;
  o.out_dir = (fs::path(::testing::TempDir()) / name).string();
  return o;
}

// DIR/frames/*, in order
std::vector<fs::path> sorted_frames(const fs::path& dir) {
  std::vector<fs::path> frames;
  for (const auto& e : fs::directory_iterator(dir / "frames")) frames.push_back(e.path());
  std::sort(frames.begin(), frames.end());
  return frames;
}

// The pulls in `whole` and `dir` end in the same state, bit for bit (with the same run
// totals), with the same curve and the same summary but for its wall-clock figures and
// the state it resumed from (and, `frames_differ`, the frames written: the run in `dir` went
// on without).
void expect_same_end(const fs::path& whole, const fs::path& dir, bool frames_differ = false) {
  const StateFile a = read_state_file((whole / "final.kstate").string());
  const StateFile b = read_state_file((dir / "final.kstate").string());
  EXPECT_EQ(a.state.time, b.state.time);
  EXPECT_TRUE(a.state.q == b.state.q);
  EXPECT_TRUE(a.state.v == b.state.v);
  if (!frames_differ)
    EXPECT_EQ(file_text((whole / "final.kstate").string()),
              file_text((dir / "final.kstate").string()));
  EXPECT_EQ(file_text((whole / "stretch.csv").string()), file_text((dir / "stretch.csv").string()));
  std::ifstream in_a(whole / "summary.json"), in_b(dir / "summary.json");
  nlohmann::json sa = nlohmann::json::parse(in_a), sb = nlohmann::json::parse(in_b);
  for (const char* k : {"wall_time_s", "wall_s_per_simulated_s", "us_per_segment_step",
                        "stage_seconds", "checkpoints_written", "resumed_from"}) {
    sa.erase(k);
    sb.erase(k);
  }
  if (frames_differ) {
    sa.erase("frames_written");
    sb.erase("frames_written");
  }
  for (const auto& [k, v] : sa.items())
    EXPECT_EQ(v, sb.value(k, nlohmann::json()))
        << k << ": resumed " << sb.value(k, nlohmann::json());
  for (const auto& [k, v] : sb.items())
    EXPECT_TRUE(sa.contains(k)) << "only the resumed run has " << k;
}

// A pull killed partway (its frames after the third gone, no summary, no final state) and
// resumed from its directory ends where the uninterrupted pull ends, with the same curve;
// a resume from an interrupt's final.kstate between two samples, too; a resume with
// another speed, a held pull or --overwrite is refused before anything changes.
TEST(Stretch, AKilledPullResumedFromItsDirectoryEndsAsTheWholeOne) {
  const fs::path tmp = ::testing::TempDir();
  const StretchOptions o = small_pull("stretch_whole");
  const StretchResult whole = stretch_knit(relaxed_sample(), o);
  ASSERT_EQ(whole.report.summary["status"], "ok");
  ASSERT_GE(whole.curve.size(), 6u);

  // killed after its third sample: frames 3… and the end's files never written
  const fs::path killed = tmp / "stretch_killed";
  fs::remove_all(killed);
  fs::copy(o.out_dir, killed, fs::copy_options::recursive);
  for (const char* f : {"summary.json", "final.kstate", "stretch_force.png", "stretch_width.png"})
    fs::remove(killed / f);
  const std::vector<fs::path> frames = sorted_frames(killed);
  ASSERT_EQ(frames.size(), whole.curve.size());
  for (size_t k = 3; k < frames.size(); ++k) fs::remove(frames[k]);
  EXPECT_EQ(stretch_resume_state(killed.string()), frames[2].string());

  StretchOptions again = o;
  again.out_dir = killed.string();
  again.overwrite = false;
  again.resume = killed.string();
  auto refused = [&](StretchOptions bad) {
    try {
      stretch_knit(relaxed_sample(), bad);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  StretchOptions faster = again;
  faster.speed = 10;
  EXPECT_NE(refused(faster).find("strain"), std::string::npos) << refused(faster);
  StretchOptions erase = again;
  erase.overwrite = true;
  EXPECT_NE(refused(erase).find("--overwrite"), std::string::npos) << refused(erase);
  StretchOptions held = again;
  held.hold_strain = 0.01;
  EXPECT_NE(refused(held).find("held"), std::string::npos) << refused(held);
  StretchOptions elsewhere = again;
  elsewhere.resume = (fs::path(o.out_dir) / "final.kstate").string();
  EXPECT_NE(refused(elsewhere).find("not a state of the run"), std::string::npos)
      << refused(elsewhere);
  EXPECT_EQ(fs::exists(killed / "summary.json"), false) << "a refused resume wrote its summary";

  const StretchResult resumed = stretch_knit(relaxed_sample(), again);
  ASSERT_EQ(resumed.report.summary["status"], "ok") << resumed.report.summary.dump(2);
  EXPECT_EQ(resumed.report.summary["resumed_from"], frames[2].string());
  expect_same_end(o.out_dir, killed);
  ASSERT_EQ(resumed.curve.size(), whole.curve.size());
  // the curve read back has stretch.csv's ten digits
  const double work = whole.report.summary["stretch"]["work_erg"].get<double>();
  EXPECT_NEAR(resumed.report.summary["stretch"]["work_erg"].get<double>(), work, 1e-8 * work);

  // interrupted one step in (SIGINT): its final.kstate lies between two samples, and the
  // next frame's sample takes the place of that state's
  const fs::path stopped = tmp / "stretch_stopped";
  StretchOptions first = o;
  first.out_dir = stopped.string();
  {
    InterruptHandler handler;
    request_interrupt(SIGINT);
    const StretchResult r = stretch_knit(relaxed_sample(), first);
    clear_interrupt();
    ASSERT_EQ(r.report.summary["status"], "interrupted");
    ASSERT_EQ(r.curve.size(), 2u);
  }
  EXPECT_EQ(stretch_resume_state(stopped.string()), (stopped / "final.kstate").string());
  StretchOptions rest = again;
  rest.out_dir = stopped.string();
  rest.resume = (stopped / "final.kstate").string();
  const StretchResult r = stretch_knit(relaxed_sample(), rest);
  ASSERT_EQ(r.report.summary["status"], "ok") << r.report.summary.dump(2);
  expect_same_end(o.out_dir, stopped);
}

// A pull without frames killed outright keeps only its last checkpoint (RunOptions::
// checkpoint_every_s): final.kstate and a summary that says "running". Its directory
// resumes from that state, and the pull ends as the uninterrupted one.
TEST(Stretch, APullWithoutFramesGoesOnFromItsCheckpoint) {
  const fs::path tmp = ::testing::TempDir();
  const StretchOptions o = small_pull("stretch_ckpt_whole");
  const StretchResult whole = stretch_knit(relaxed_sample(), o);
  ASSERT_EQ(whole.report.summary["status"], "ok");
  const std::vector<fs::path> frames = sorted_frames(o.out_dir);
  ASSERT_GE(frames.size(), 4u);

  // as the pull without frames left it, killed after a checkpoint at its third sample
  const fs::path killed = tmp / "stretch_ckpt_killed";
  fs::remove_all(killed);
  fs::copy(o.out_dir, killed, fs::copy_options::recursive);
  fs::remove_all(killed / "frames");
  for (const char* f : {"stretch_force.png", "stretch_width.png"}) fs::remove(killed / f);
  fs::copy_file(frames[2], killed / "final.kstate", fs::copy_options::overwrite_existing);
  std::ofstream(killed / "summary.json") << R"({"status": "running"})";
  EXPECT_EQ(stretch_resume_state(killed.string()), (killed / "final.kstate").string());

  StretchOptions again = o;
  again.out_dir = killed.string();
  again.overwrite = false;
  again.write_frames = false;
  again.resume = killed.string();
  const StretchResult resumed = stretch_knit(relaxed_sample(), again);
  ASSERT_EQ(resumed.report.summary["status"], "ok") << resumed.report.summary.dump(2);
  expect_same_end(o.out_dir, killed, true);

  // a checkpoint whose time has no sample in stretch.csv is not taken
  fs::remove_all(killed);
  fs::copy(o.out_dir, killed, fs::copy_options::recursive);
  fs::remove_all(killed / "frames");
  std::ofstream(killed / "summary.json") << R"({"status": "running"})";
  {  // the header and the first sample (t = 0) only: the end state has none
    const std::string csv = file_text(o.out_dir + "/stretch.csv");
    std::ofstream(killed / "stretch.csv", std::ios::trunc)
        << csv.substr(0, csv.find('\n', csv.find('\n') + 1) + 1);
  }
  EXPECT_THROW(stretch_resume_state(killed.string()), std::invalid_argument);
}

TEST(Stretch, BadOptionsAreRefusedBeforeAnythingIsWritten) {
  const std::string out = (fs::path(::testing::TempDir()) / "stretch_bad").string();
  fs::remove_all(out);
  EXPECT_THROW(parse_stretch_direction("diagonal"), std::invalid_argument);
  auto message = [&](StretchOptions o) {
    o.out_dir = out;
    o.progress = false;
    try {
      stretch_knit(relaxed_sample(), o);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  StretchOptions zero;
  zero.to_strain = 0;
  EXPECT_NE(message(zero).find("--to"), std::string::npos);
  StretchOptions slow;
  slow.speed = -1;
  EXPECT_NE(message(slow).find("--speed"), std::string::npos);
  StretchOptions wide;
  wide.direction = StretchDirection::WALE;
  wide.clamp_stitches = 3;  // 5 rows cannot hold two clamps of 3
  EXPECT_NE(message(wide).find("need at least 7"), std::string::npos) << message(wide);
  StretchOptions steps;
  steps.to_strain = 0.2;
  steps.hold_strain = 0.3;  // a step beyond the whole pull
  EXPECT_NE(message(steps).find("--hold"), std::string::npos) << message(steps);
  StretchOptions still;
  still.hold_strain = 0.1;
  still.hold_time = 0;
  EXPECT_NE(message(still).find("--hold-time"), std::string::npos) << message(still);
  StretchOptions limit;
  limit.max_force = -1;
  EXPECT_NE(message(limit).find("--max-force"), std::string::npos) << message(limit);
  EXPECT_FALSE(fs::exists(out)) << "a refused stretch wrote its directory";
}

}  // namespace
}  // namespace knit
