// The knitsim program end to end: exit codes, messages, and that nothing is written when
// a scene is rejected.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "knit/io/state_file.hpp"
#include "knit/run/relaxation.hpp"
#include "run_knitsim.hpp"

namespace {

namespace fs = std::filesystem;

using knit::cli_test::Result;
using knit::cli_test::run;
using knit::cli_test::temp_dir;

TEST(Cli, RejectedSceneWritesNothing) {
  const std::string scene = ::testing::TempDir() + "/cli_bad.json";
  std::ofstream(scene) << R"({"yarns": [{"line": {"from": [0,0,0], "to": [1,0,0], "segments": 4}}],
                              "pins": [{"yarn": 2, "at": "start"}]})";
  const std::string out = temp_dir("cli_bad_out");
  const Result r = run("simulate " + scene + " --out " + out);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("pins[0].yarn"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out)) << "output directory created for a rejected scene";
}

TEST(Cli, PendulumExampleRunsAndSummarises) {
  const std::string out = temp_dir("cli_pendulum");
  const Result r = run(std::string("simulate ") + KNIT_EXAMPLES + "/pendulum.json --out " + out +
                       " --duration 0.05 --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  for (const char* key :
       {"status", "steps", "sim_time_s", "wall_time_s", "threads", "yarns", "segments",
        "control_points", "max_length_violation", "kinetic_energy", "potential_energy"})
    EXPECT_TRUE(s.contains(key)) << key;
  EXPECT_EQ(s["status"], "ok");
  EXPECT_EQ(s["steps"], 500);
  EXPECT_LT(s["max_length_violation"].get<double>(), 1e-6);
  EXPECT_TRUE(fs::exists(out + "/final.kstate"));
  EXPECT_TRUE(fs::exists(out + "/log.csv"));
  EXPECT_TRUE(fs::exists(out + "/frames/state_000005.kstate"));
}

// --integrator, --implicit-bending and --time-step override the scene's: the summary
// records what ran, and an integrator that does not exist is refused by name.
TEST(Cli, SimulateTakesTheIntegratorTimeStepAndOutputIntervalAsked) {
  const std::string out = temp_dir("cli_imex");
  const Result r = run(std::string("simulate ") + KNIT_EXAMPLES + "/pendulum.json --out " + out +
                       " --duration 0.05 --time-step 2e-4 --integrator imex --implicit-bending "
                       "--output-every 60 --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_EQ(s["params"]["solver"]["integrator"], "imex");
  EXPECT_EQ(s["params"]["solver"]["implicit_bending"], true);
  EXPECT_EQ(s["steps"], 250);
  // --output-every: the initial state, steps 60, 120, 180, 240, and the last
  std::ifstream log(out + "/log.csv");
  int rows = -1;  // the header
  for (std::string line; std::getline(log, line);) ++rows;
  EXPECT_EQ(rows, 6);
  EXPECT_GT(s["stage_seconds"].value("implicit", 0.0), 0.0) << "the implicit stage never ran";
  const Result bad = run(std::string("simulate ") + KNIT_EXAMPLES + "/pendulum.json --out " +
                         temp_dir("cli_imex_bad") + " --integrator implicit");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.output.find("--integrator"), std::string::npos) << bad.output;
  const std::string bad_step_out = temp_dir("cli_imex_bad_step");
  const Result bad_step = run(std::string("simulate ") + KNIT_EXAMPLES + "/pendulum.json --out " +
                              bad_step_out + " --time-step 1");
  EXPECT_NE(bad_step.code, 0);
  EXPECT_NE(bad_step.output.find("--time-step"), std::string::npos) << bad_step.output;
  EXPECT_FALSE(fs::exists(bad_step_out)) << "output directory created for a refused step";
}

// --contact-solve-tolerance overrides the scene's: with it the imex-contact solve iterates
// (the summary's implicit_solve), without it not; a value outside [0, 1] is refused by name
// before anything is written.
TEST(Cli, SimulateTakesTheContactSolveTolerance) {
  auto simulate = [](const std::string& out, const std::string& extra) {
    return run(std::string("simulate ") + KNIT_EXAMPLES + "/hanging_knit.json --out " + out +
               " --duration 0.008 --time-step 4e-4 --integrator imex-contact --quiet" + extra);
  };
  const std::string out = temp_dir("cli_contact_cg");
  const Result r = simulate(out, " --contact-solve-tolerance 1e-6");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_EQ(s["params"]["solver"]["contact_solve_tolerance"], 1e-6);
  ASSERT_TRUE(s.contains("implicit_solve")) << "the solve did not iterate";
  EXPECT_GT(s["implicit_solve"]["iterations_mean"].get<double>(), 0.0);
  const std::string lagged = temp_dir("cli_contact_lagged");
  ASSERT_EQ(simulate(lagged, "").code, 0);
  std::ifstream lagged_in(lagged + "/summary.json");
  const auto l = nlohmann::json::parse(lagged_in);
  EXPECT_EQ(l["params"]["solver"]["contact_solve_tolerance"], 0.0);
  EXPECT_FALSE(l.contains("implicit_solve")) << "the lagged solve reports no iterations";
  const std::string bad_out = temp_dir("cli_contact_cg_bad");
  const Result bad = simulate(bad_out, " --contact-solve-tolerance 2");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.output.find("--contact-solve-tolerance"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(bad_out)) << "output directory created for a refused tolerance";
}

TEST(Cli, UnstableRunStopsWithStatusAndKeepsLastGoodState) {
  const std::string scene = ::testing::TempDir() + "/cli_unstable.json";
  std::ofstream(scene) << R"({"yarns": [{"line": {"from": [0,0,0], "to": [5,0,0], "segments": 10}}],
                              "params": {"k_bend": 1e6}, "time_step": 0.01, "duration": 1})";
  const std::string out = temp_dir("cli_unstable_out");
  const Result r = run("simulate " + scene + " --out " + out + " --quiet");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("smaller time step"), std::string::npos) << r.output;
  std::ifstream in(out + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_NE(s["status"], "ok");
  EXPECT_TRUE(fs::exists(out + "/last_good.kstate"));
}

TEST(Cli, UnknownOptionFails) {
  const Result r = run("simulate --bogus");
  EXPECT_NE(r.code, 0);
}

}  // namespace

namespace {

TEST(Cli, RelaxSmallSwatchWritesShapeSummaryAndExport) {
  const std::string out = temp_dir("cli_relax");
  const Result r =
      run("relax stockinette --rows 4 --cols 5 --max-time 0.005 --quiet --export glb --out " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  for (const char* key : {"pattern", "rows", "cols", "course_extent_cm", "wale_extent_cm",
                          "thickness_cm", "stitch_width_cm", "row_height_cm", "loop_length_cm",
                          "edge_curl", "relaxed", "ke_per_length", "ke_per_length_threshold",
                          "min_contact_distance", "k_global", "alpha_small", "alpha_large"})
    EXPECT_TRUE(s.contains(key)) << key;
  EXPECT_EQ(s["k_global"].get<double>(), knit::RELAX_K_GLOBAL);
  EXPECT_EQ(s["alpha_small"].get<double>(), 0.3);
  EXPECT_EQ(s["rows"], 4);
  EXPECT_EQ(s["cols"], 5);
  // 0.005 s (59 steps) into the relaxation the swatch is still nearly as generated: a
  // gauge of 0.98 cm per stitch and 0.74 cm per row (KnitOptions' documented loop),
  // measured 0.978 and 0.726 (rows draw together first); allowed ±2 % and ±4 %. The
  // shrunk rest lengths have begun to draw it in across: course extent measured 0.961 of
  // the generated one (allowed 0.92–0.99), wale extent 0.9998 (allowed 0.97–1.01); no edge
  // has rolled yet (edge curl measured 0.059, allowed 0.1).
  EXPECT_NEAR(s["stitch_width_cm"].get<double>(), 0.98, 0.02 * 0.98);
  EXPECT_NEAR(s["row_height_cm"].get<double>(), 0.74, 0.04 * 0.74);
  const auto& generated = s["generated"]["shape"];
  const double course = s["course_extent_cm"].get<double>() /
                        generated["course_extent_cm"].get<double>(),
               wale = s["wale_extent_cm"].get<double>() / generated["wale_extent_cm"].get<double>();
  EXPECT_GT(course, 0.92);
  EXPECT_LT(course, 0.99);
  EXPECT_GT(wale, 0.97);
  EXPECT_LT(wale, 1.01);
  EXPECT_LT(s["edge_curl"].get<double>(), 0.1);
  for (const char* f : {"/initial.kstate", "/relaxed.kstate", "/final.glb", "/log.csv"})
    EXPECT_TRUE(fs::exists(out + f)) << f;
}

TEST(Cli, RelaxTakesThePapersGlobalDampingWhenAsked) {
  const std::string out = temp_dir("cli_relax_damped");
  const Result r =
      run("relax garter --rows 3 --cols 3 --max-time 0.002 --quiet --no-frames --k-global 1.5 "
          "--alpha-large 0.5 --out " +
          out);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_EQ(s["k_global"].get<double>(), 1.5);
  EXPECT_EQ(s["alpha_large"].get<double>(), 0.5);
  EXPECT_GT(s["stage_seconds"]["global_damping"].get<double>(), 0.0);
  const Result bad = run("relax garter --alpha-small 2 --out " + out + "_bad");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.output.find("alpha-small"), std::string::npos) << bad.output;
}

// `relax --fire` relaxes by minimisation: no damping (refused if asked), the FIRE filter,
// rest by the force residual, which the log records at every check.
TEST(Cli, RelaxFireRestsByTheForceResidual) {
  const std::string out = temp_dir("cli_relax_fire");
  const Result r =
      run("relax stockinette --rows 3 --cols 3 --fire --integrator imex --time-step 3e-4 "
          "--max-time 0.03 --check-every 20 --residual 1e9 --quiet --no-frames --out " +
          out);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("at rest"), std::string::npos) << r.output;
  std::ifstream in(out + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_EQ(s["method"], "fire");
  EXPECT_EQ(s["rest_test"], "residual");
  EXPECT_EQ(s["force_residual_threshold"].get<double>(), 1e9);
  EXPECT_GT(s["force_residual"].get<double>(), 0.0);
  std::ifstream log(out + "/log.csv");
  std::string header;
  std::getline(log, header);
  EXPECT_NE(header.find(",force_residual,"), std::string::npos) << header;
  for (const char* damping : {"--k-global 1", "--alpha-small 0.2"}) {
    const Result bad =
        run(std::string("relax stockinette --fire ") + damping + " --out " + out + "_bad");
    EXPECT_NE(bad.code, 0);
    EXPECT_NE(bad.output.find("FIRE"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(out + "_bad"));
  }
}

// `relax --contact-reuse` reuses contact's linearisation (imex-contact): the summary says in
// how many steps; with another integrator, or out of range, it is refused by name before
// anything is written. `--contact-reuse-widen` widens its distance far from rest.
TEST(Cli, RelaxTakesTheContactReuse) {
  const std::string out = temp_dir("cli_relax_reuse");
  const Result r =
      run("relax garter --rows 3 --cols 3 --fire --integrator imex-contact --time-step 6e-4 "
          "--contact-reuse 0.05 --max-time 0.3 --check-every 25 --quiet --no-frames --out " +
          out);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_EQ(s["params"]["solver"]["contact_reuse"].get<double>(), 0.05);
  EXPECT_GT(s["contact_linearised_fraction"].get<double>(), 0.0);
  EXPECT_GT(s["matrix_kept_fraction"].get<double>(), 0.0);
  EXPECT_EQ(s["contact_reuse_scale_mean"].get<double>(), 1.0);
  EXPECT_FALSE(s.contains("contact_reuse_widen"));
  // widened far from rest: the generated knit's residual is far above 1 cm/s², so the
  // steps until the first checks run at the widest
  const Result wide =
      run("relax garter --rows 3 --cols 3 --fire --integrator imex-contact --time-step 6e-4 "
          "--contact-reuse 0.05 --contact-reuse-widen 3 --contact-reuse-widen-residual 1 "
          "--max-time 0.03 --check-every 25 --quiet --no-frames --out " +
          out + "_wide");
  ASSERT_EQ(wide.code, 0) << wide.output;
  std::ifstream in_wide(out + "_wide/summary.json");
  const auto w = nlohmann::json::parse(in_wide);
  EXPECT_EQ(w["contact_reuse_widen"]["max"].get<double>(), 3.0);
  EXPECT_EQ(w["contact_reuse_widen"]["residual"].get<double>(), 1.0);
  EXPECT_GT(w["contact_reuse_scale_mean"].get<double>(), 2.0);
  EXPECT_LE(w["contact_reuse_scale_mean"].get<double>(), 3.0);
  // resumed in place (no output at the start), with no check in its 25 steps: widened from
  // its first step by the state it starts from (the summary covers the whole run: its 50
  // steps at the scale it had and these 25 at 3)
  const Result again =
      run("relax --fire --integrator imex-contact --time-step 6e-4 --contact-reuse 0.05 "
          "--contact-reuse-widen 3 --contact-reuse-widen-residual 1 --max-time 0.015 "
          "--check-every 1000 --quiet --no-frames --resume " +
          out + "_wide/final.kstate --out " + out + "_wide");
  ASSERT_EQ(again.code, 0) << again.output;
  std::ifstream in_again(out + "_wide/summary.json");
  const auto a = nlohmann::json::parse(in_again);
  const int first = w["steps"].get<int>();
  ASSERT_EQ(a["steps"].get<int>(), first + 25);
  EXPECT_NEAR(a["contact_reuse_scale_mean"].get<double>() * (first + 25) -
                  w["contact_reuse_scale_mean"].get<double>() * first,
              3.0 * 25, 1e-9);
  // widening without reuse, or narrowing, is refused by name before anything is written
  const Result unused = run(
      "relax garter --fire --integrator imex-contact --contact-reuse-widen 2 --out " + out + "_u");
  EXPECT_NE(unused.code, 0);
  EXPECT_NE(unused.output.find("contact-reuse-widen"), std::string::npos) << unused.output;
  EXPECT_NE(unused.output.find("--contact-reuse "), std::string::npos) << unused.output;
  EXPECT_FALSE(fs::exists(out + "_u"));
  const Result narrow = run(
      "relax garter --fire --integrator imex-contact --contact-reuse 0.05 --contact-reuse-widen "
      "0.5 --out " +
      out + "_n");
  EXPECT_NE(narrow.code, 0);
  EXPECT_NE(narrow.output.find("--contact-reuse-widen"), std::string::npos) << narrow.output;
  EXPECT_FALSE(fs::exists(out + "_n"));
  const Result other =
      run("relax garter --integrator imex --contact-reuse 0.05 --out " + out + "_imex");
  EXPECT_NE(other.code, 0);
  EXPECT_NE(other.output.find("contact_reuse"), std::string::npos) << other.output;
  EXPECT_NE(other.output.find("imex-contact"), std::string::npos) << other.output;
  EXPECT_FALSE(fs::exists(out + "_imex"));
  const Result range =
      run("relax garter --integrator imex-contact --contact-reuse 2 --out " + out + "_range");
  EXPECT_NE(range.code, 0);
  EXPECT_NE(range.output.find("--contact-reuse"), std::string::npos) << range.output;
  EXPECT_FALSE(fs::exists(out + "_range"));
}

// `relax` takes the solver options `simulate` and `stretch` take (implicit bending, the
// contact solve's tolerance, the end mass floor): they reach the run's parameters; a FIRE
// run counts its restarts; out of range they are refused by name, nothing written.
TEST(Cli, RelaxTakesTheSolverOptions) {
  const std::string out = temp_dir("cli_relax_solver");
  const Result r =
      run("relax garter --rows 3 --cols 3 --fire --integrator imex-contact --time-step 6e-4 "
          "--implicit-bending --contact-solve-tolerance 0.01 --end-mass-floor 0.5 --max-time 0.03 "
          "--max-step-halvings 2 --check-every 25 --quiet --no-frames --out " +
          out);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_TRUE(s["params"]["solver"]["implicit_bending"].get<bool>());
  EXPECT_EQ(s["params"]["solver"]["contact_solve_tolerance"].get<double>(), 0.01);
  EXPECT_EQ(s["params"]["discretisation"]["end_mass_floor"].get<double>(), 0.5);
  EXPECT_EQ(s["params"]["solver"]["max_step_halvings"].get<int>(), 2);
  EXPECT_GE(s["step_halvings"]["substeps"].get<long long>(), s["steps"].get<long long>());
  EXPECT_GT(s["implicit_solve"]["steps"].get<long long>(), 0);  // the solve iterated
  EXPECT_GE(s["fire_restarts"].get<long long>(), 0);
  // where the residual sits: its largest point's acceleration is at least the RMS, and the
  // top 1 % of points hold at least 1 % of its square
  const auto& peak = s["force_residual_peak"];
  EXPECT_GE(peak["acceleration"].get<double>(), s["force_residual"].get<double>());
  EXPECT_GE(peak["top_percent_share"].get<double>(), 0.01);
  EXPECT_LE(peak["top_percent_share"].get<double>(), 1.0);
  EXPECT_EQ(peak["yarn"].get<int>(), 0);
  EXPECT_EQ(peak["position_cm"].size(), 3u);
  for (const char* bad :
       {"--end-mass-floor 2", "--contact-solve-tolerance 5", "--max-step-halvings 30"}) {
    const Result refused = run(std::string("relax garter --integrator imex-contact ") + bad +
                               " --out " + out + "_bad");
    EXPECT_NE(refused.code, 0);
    EXPECT_NE(refused.output.find(std::string(bad).substr(0, std::string(bad).find(' '))),
              std::string::npos)
        << refused.output;
    EXPECT_FALSE(fs::exists(out + "_bad"));
  }
}

// A relaxation stopped and resumed (--resume) follows the same path as one that ran on:
// the state file holds positions, velocities and time, and the glues go on closing.
TEST(Cli, ResumedRelaxationContinuesTheSamePath) {
  const std::string dir = temp_dir("cli_resume");
  const std::string opts = " --rows 3 --cols 4 --quiet --no-frames --threads 1";
  ASSERT_EQ(run("relax garter" + opts + " --max-time 0.03 --out " + dir + "/whole").code, 0);
  ASSERT_EQ(run("relax garter" + opts + " --max-time 0.01 --out " + dir + "/first").code, 0);
  const Result r = run("relax garter" + opts + " --max-time 0.02 --resume " + dir +
                       "/first/relaxed.kstate --out " + dir + "/second");
  ASSERT_EQ(r.code, 0) << r.output;
  const knit::StateFile whole = knit::read_state_file(dir + "/whole/relaxed.kstate");
  const knit::StateFile resumed = knit::read_state_file(dir + "/second/relaxed.kstate");
  // the same steps from the same state: bit for bit
  EXPECT_EQ(resumed.state.time, whole.state.time);
  EXPECT_TRUE(resumed.state.q == whole.state.q);
  EXPECT_TRUE(resumed.state.v == whole.state.v);

  // a state of another pattern or size is refused, naming what differs
  const Result other =
      run("relax rib2x2" + opts + " --resume " + dir + "/first/relaxed.kstate --out " + dir + "/x");
  EXPECT_EQ(other.code, 1);
  EXPECT_NE(other.output.find("relaxed from pattern garter"), std::string::npos) << other.output;
  const Result size = run("relax garter --rows 4 --cols 4 --resume " + dir +
                          "/first/relaxed.kstate --out " + dir + "/y");
  EXPECT_EQ(size.code, 1);
  EXPECT_NE(size.output.find("control points"), std::string::npos) << size.output;
  const Result round = run("relax garter" + opts + " --round --resume " + dir +
                           "/first/relaxed.kstate --out " + dir + "/z");
  EXPECT_EQ(round.code, 1);
  EXPECT_NE(round.output.find("knitted flat"), std::string::npos) << round.output;
  EXPECT_FALSE(fs::exists(dir + "/y"));
}

// A run resumed in its own directory appends to its log.csv; a log with other columns
// (written by an older knitsim) is kept whole beside it, never mixed into it.
TEST(Cli, ResumingInPlaceKeepsALogOfOtherColumnsAside) {
  const std::string dir = temp_dir("cli_resume_log");
  const std::string opts = " --rows 3 --cols 3 --quiet --check-every 20 --threads 1";
  ASSERT_EQ(run("relax garter" + opts + " --max-time 0.005 --out " + dir).code, 0);
  auto lines = [](const std::string& path) {
    std::ifstream in(path);
    std::vector<std::string> out;
    for (std::string line; std::getline(in, line);) out.push_back(line);
    return out;
  };
  std::vector<std::string> old = lines(dir + "/log.csv");
  ASSERT_GT(old.size(), 1u);
  const std::string header = old[0];
  const size_t col = header.find(",force_residual");
  ASSERT_NE(col, std::string::npos) << header;
  old[0] = header.substr(0, col) + header.substr(col + std::string(",force_residual").size());
  {
    std::ofstream out(dir + "/log.csv");
    for (const std::string& line : old) out << line << "\n";
  }
  const Result r =
      run("relax" + opts + " --max-time 0.005 --resume " + dir + "/final.kstate --out " + dir);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(lines(dir + "/log_before_resume.csv"), old);
  const std::vector<std::string> now = lines(dir + "/log.csv");
  ASSERT_GT(now.size(), 1u);
  EXPECT_EQ(now[0], header);
  const auto fields = [](const std::string& line) {
    return std::count(line.begin(), line.end(), ',');
  };
  for (const std::string& line : now) EXPECT_EQ(fields(line), fields(header)) << line;
}

TEST(Cli, RelaxRejectsUnknownPatternAndWritesNothing) {
  const std::string out = temp_dir("cli_relax_bad");
  const Result r = run("relax plainweave --rows 4 --cols 4 --out " + out);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("plainweave"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  const Result r2 = run("relax --out " + out);
  EXPECT_NE(r2.code, 0);
  EXPECT_NE(r2.output.find("PATTERN or --from"), std::string::npos) << r2.output;
}

TEST(Cli, SceneCanImportYarnFiles) {
  const std::string scene = ::testing::TempDir() + "/cli_import.json";
  std::ofstream(scene)
      << R"({"yarns": [{"import": {"path": ")" << KNIT_TEST_DATA
      << R"(/yarns/knit-2x2.yarns"}}], "gravity": [0,0,0], "params": {"contact": false},
                              "time_step": 0.00002, "duration": 0.0002})";
  const std::string out = temp_dir("cli_import_out");
  const Result r = run("simulate " + scene + " --quiet --out " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out + "/summary.json");
  EXPECT_GT(nlohmann::json::parse(in)["segments"].get<int>(), 50);
  std::ofstream(scene) << R"({"yarns": [{"import": "missing.yarns"}]})";
  const Result bad = run("simulate " + scene + " --out " + out + "_bad");
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.output.find("yarns[0].import"), std::string::npos) << bad.output;
}

}  // namespace

namespace {

TEST(Cli, RenderingARunDirectoryRendersItsFrames) {
  const std::string out = temp_dir("cli_run_frames");
  ASSERT_EQ(run(std::string("simulate ") + KNIT_EXAMPLES +
                "/pendulum.json --duration 0.02 --quiet --out " + out)
                .code,
            0);
  const std::string png = temp_dir("cli_run_frames_png");
  // at a given frame rate every state is a frame (at real time, 100 states per second
  // would be thinned to 50)
  const Result r = run("render " + out + " --out " + png + " --size 64x48 --spp 1 --fps 30");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::exists(png + "/frame_0002.png")) << r.output;  // initial + 2 outputs
}

}  // namespace

namespace {

// A run never mixes its files with another run's: a directory holding files is refused
// (nothing in it touched) unless --overwrite, which empties it first.
TEST(Cli, RunDirectoriesAreNeverMixed) {
  const std::string out = temp_dir("cli_mixed");
  const std::string pendulum = std::string(KNIT_EXAMPLES) + "/pendulum.json --quiet";
  ASSERT_EQ(run("simulate " + pendulum + " --duration 0.05 --out " + out).code, 0);
  ASSERT_TRUE(fs::exists(out + "/frames/state_000005.kstate"));
  const Result again = run("simulate " + pendulum + " --duration 0.01 --out " + out);
  EXPECT_EQ(again.code, 1);
  EXPECT_NE(again.output.find("--overwrite"), std::string::npos) << again.output;
  EXPECT_TRUE(fs::exists(out + "/frames/state_000005.kstate")) << "the earlier run was touched";
  const Result over = run("simulate " + pendulum + " --duration 0.01 --overwrite --out " + out);
  ASSERT_EQ(over.code, 0) << over.output;
  EXPECT_FALSE(fs::exists(out + "/frames/state_000005.kstate")) << "old frames left behind";
  EXPECT_TRUE(fs::exists(out + "/frames/state_000001.kstate"));
  const Result relax = run("relax garter --rows 2 --cols 2 --max-time 0.001 --quiet --out " + out);
  EXPECT_EQ(relax.code, 1);
  EXPECT_NE(relax.output.find("already holds an earlier run's files"), std::string::npos)
      << relax.output;
  for (const char* bad : {"/", "~"}) {
    const Result r = run("simulate " + pendulum + " --duration 0.001 --overwrite --out " + bad);
    EXPECT_EQ(r.code, 1) << bad;
    EXPECT_NE(r.output.find("refusing"), std::string::npos) << r.output;
  }
}

}  // namespace

namespace {

// relaxed.kstate says which knit it holds: --resume alone goes on with its pattern, size
// and shrink, exactly as naming them would
TEST(Cli, ResumeTakesTheKnitFromTheStateFile) {
  const std::string dir = temp_dir("cli_resume_alone");
  const std::string opts = " --quiet --no-frames --threads 1 --max-time 0.005";
  ASSERT_EQ(run("relax rib2x2 --rows 3 --cols 4 --round --shrink 0.95" + opts + " --out " + dir +
                "/first")
                .code,
            0);
  const std::string first = dir + "/first/relaxed.kstate";
  const Result alone = run("relax --resume " + first + opts + " --out " + dir + "/alone");
  ASSERT_EQ(alone.code, 0) << alone.output;
  const Result named = run("relax rib2x2 --rows 3 --cols 4 --round --shrink 0.95 --resume " +
                           first + opts + " --out " + dir + "/named");
  ASSERT_EQ(named.code, 0) << named.output;
  const knit::StateFile a = knit::read_state_file(dir + "/alone/relaxed.kstate");
  const knit::StateFile b = knit::read_state_file(dir + "/named/relaxed.kstate");
  EXPECT_EQ(a.state.q, b.state.q);
  ASSERT_TRUE(a.knit.has_value());
  EXPECT_EQ(a.knit->pattern, "rib2x2");
  EXPECT_TRUE(a.knit->in_the_round);
  EXPECT_EQ(a.knit->shrink, 0.95);
  std::ifstream in(dir + "/alone/summary.json");
  EXPECT_EQ(nlohmann::json::parse(in)["rows"], 3);
}

// A relaxation's states say how it was relaxing: --resume alone goes on the same way (the
// method, integrator, time step, contact reuse and its widening, rest test), step for
// step as repeating every option does; an option given wins; --no-fire goes on by damped
// dynamics, and damping asked of a resumed FIRE relaxation is refused naming --no-fire.
TEST(Cli, ResumeGoesOnAsTheRelaxationWent) {
  const std::string dir = temp_dir("cli_resume_solver");
  const std::string solver =
      " --fire --integrator imex-contact --time-step 6e-4 --contact-reuse 0.05 "
      "--contact-reuse-widen 2 --contact-reuse-widen-residual 10 --check-every 25";
  const std::string opts = " --quiet --no-frames --threads 1 --max-time 0.015";
  ASSERT_EQ(run("relax garter --rows 3 --cols 3" + solver + opts + " --out " + dir + "/first").code,
            0);
  const std::string first = dir + "/first/final.kstate";
  const Result alone = run("relax --resume " + first + opts + " --out " + dir + "/alone");
  ASSERT_EQ(alone.code, 0) << alone.output;
  const Result named = run("relax garter --rows 3 --cols 3 --resume " + first + solver + opts +
                           " --out " + dir + "/named");
  ASSERT_EQ(named.code, 0) << named.output;
  const knit::StateFile a = knit::read_state_file(dir + "/alone/final.kstate");
  const knit::StateFile b = knit::read_state_file(dir + "/named/final.kstate");
  EXPECT_EQ(a.state.time, b.state.time);
  EXPECT_TRUE(a.state.q == b.state.q);
  EXPECT_TRUE(a.state.v == b.state.v);
  auto summary = [&](const std::string& name) {
    std::ifstream in(dir + "/" + name + "/summary.json");
    return nlohmann::json::parse(in);
  };
  const nlohmann::json s = summary("alone");
  EXPECT_EQ(s["method"], "fire");
  EXPECT_EQ(s["rest_test"], "residual");
  EXPECT_EQ(s["steps"], 25);  // 0.015 s at 6e-4 s, not at 1/11800 s
  EXPECT_EQ(s["params"]["solver"]["integrator"], "imex-contact");
  EXPECT_EQ(s["params"]["solver"]["time_step"], 6e-4);
  EXPECT_EQ(s["params"]["solver"]["contact_reuse"], 0.05);
  EXPECT_EQ(s["contact_reuse_widen"]["max"], 2.0);
  EXPECT_EQ(s["contact_reuse_widen"]["residual"], 10.0);
  // and its own states say so in turn
  ASSERT_TRUE(a.knit && a.knit->relaxation);
  EXPECT_TRUE(a.knit->relaxation->fire);
  EXPECT_EQ(a.knit->relaxation->check_every, 25);
  // an option given wins over the file's
  ASSERT_EQ(
      run("relax --resume " + first + " --time-step 5e-4" + opts + " --out " + dir + "/step").code,
      0);
  EXPECT_EQ(summary("step")["params"]["solver"]["time_step"], 5e-4);
  EXPECT_EQ(summary("step")["method"], "fire");
  ASSERT_EQ(run("relax --resume " + first + " --no-fire --k-global 1" + opts + " --out " + dir +
                "/damped")
                .code,
            0);
  EXPECT_EQ(summary("damped")["method"], "damped_dynamics");
  EXPECT_EQ(summary("damped")["k_global"], 1.0);
  EXPECT_EQ(summary("damped")["params"]["solver"]["integrator"], "imex-contact");
  // another integrator leaves the file's contact reuse (imex-contact's) and its widening
  ASSERT_EQ(
      run("relax --resume " + first + " --integrator imex" + opts + " --out " + dir + "/imex").code,
      0);
  EXPECT_EQ(summary("imex")["params"]["solver"]["integrator"], "imex");
  EXPECT_EQ(summary("imex")["params"]["solver"]["contact_reuse"], 0.0);
  EXPECT_FALSE(summary("imex").contains("contact_reuse_widen"));
  EXPECT_EQ(summary("imex")["method"], "fire");
  const Result damping =
      run("relax --resume " + first + " --k-global 1" + opts + " --out " + dir + "/refused");
  EXPECT_EQ(damping.code, 1);
  EXPECT_NE(damping.output.find("--k-global"), std::string::npos) << damping.output;
  EXPECT_NE(damping.output.find("--no-fire"), std::string::npos) << damping.output;
  EXPECT_FALSE(fs::exists(dir + "/refused"));
}

// --bind-off and --cast-on: the state file says the knit is bound off (cast on) and holds
// its ties (two per loop of the last row, or of the second); --resume keeps them unless
// told otherwise, the flag on a state knitted without is refused, and so is the flag on a
// state --from in stretch
TEST(Cli, EdgeTiesAreKeptInTheStateFileAndOnResume) {
  for (const std::string flag : {"bind-off", "cast-on"}) {
    SCOPED_TRACE(flag);
    const std::string key = flag == "bind-off" ? "bind_off" : "cast_on";
    const std::string dir = temp_dir("cli_" + key);
    const std::string opts = " --quiet --no-frames --threads 1 --max-time 0.002";
    ASSERT_EQ(
        run("relax stockinette --rows 3 --cols 4 --" + flag + opts + " --out " + dir + "/first")
            .code,
        0);
    const std::string first = dir + "/first/relaxed.kstate";
    const knit::StateFile f = knit::read_state_file(first);
    ASSERT_TRUE(f.knit.has_value());
    EXPECT_EQ(f.knit->bind_off, flag == "bind-off");
    EXPECT_EQ(f.knit->cast_on, flag == "cast-on");
    EXPECT_EQ(f.glues.size(), 2u + 2 * 4);
    std::ifstream in(dir + "/first/summary.json");
    EXPECT_EQ(nlohmann::json::parse(in)[key], true);
    const Result alone = run("relax --resume " + first + opts + " --out " + dir + "/alone");
    ASSERT_EQ(alone.code, 0) << alone.output;
    const knit::StateFile a = knit::read_state_file(dir + "/alone/relaxed.kstate");
    ASSERT_TRUE(a.knit.has_value());
    EXPECT_EQ(a.knit->bind_off, f.knit->bind_off);
    EXPECT_EQ(a.knit->cast_on, f.knit->cast_on);
    EXPECT_EQ(a.glues.size(), f.glues.size());
    ASSERT_EQ(run("relax stockinette --rows 3 --cols 4" + opts + " --out " + dir + "/live").code,
              0);
    const Result tied = run("relax stockinette --rows 3 --cols 4 --" + flag + " --resume " + dir +
                            "/live/relaxed.kstate" + opts + " --out " + dir + "/tied");
    EXPECT_EQ(tied.code, 1);
    const std::string noun = flag == "bind-off" ? "a bind-off" : "a cast-on";
    EXPECT_NE(tied.output.find("without " + noun + "; give no --" + flag), std::string::npos)
        << tied.output;
    EXPECT_FALSE(fs::exists(dir + "/tied"));
    const Result stretch = run("stretch --from " + first + " --" + flag + " --out " + dir + "/s");
    EXPECT_EQ(stretch.code, 1);
    EXPECT_NE(stretch.output.find("--" + flag), std::string::npos) << stretch.output;
    EXPECT_FALSE(fs::exists(dir + "/s"));
  }
}

}  // namespace

namespace {

// the hanging-knit example: a relaxed knit from the repository, hung from its top row;
// the summary and the log carry the clamp's force
TEST(Cli, HangingKnitExampleReportsItsClamp) {
  const std::string out = temp_dir("cli_hanging_knit");
  const Result r = run(std::string("simulate ") + KNIT_EXAMPLES +
                       "/hanging_knit.json --duration 0.005 --quiet --out " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  ASSERT_TRUE(s["constraint_forces"].contains("top")) << s.dump(2);
  EXPECT_EQ(s["constraint_forces"]["top"]["kind"], "clamp");
  EXPECT_GT(s["constraint_forces"]["top"]["force"][2].get<double>(), 0.0);
  EXPECT_EQ(s["knits"].size(), 1u);
  std::ifstream log(out + "/log.csv");
  std::string header;
  std::getline(log, header);
  EXPECT_NE(header.find("top_fx,top_fy,top_fz"), std::string::npos) << header;
  EXPECT_NE(header.find("energy_contact"), std::string::npos) << header;
}

}  // namespace

namespace {

// knitsim stretch: a pattern is relaxed (once bound off) and pulled; two runs' curves go
// into one plot; a bad direction is refused with nothing written
TEST(Cli, StretchRunsAndPlotsSeveralRuns) {
  const std::string dir = temp_dir("cli_stretch");
  const std::string common = " --rows 5 --cols 6 --relax-time 0.05 --to 0.05 --quiet --no-frames";
  ASSERT_EQ(run("stretch garter" + common + " --out " + dir + "/course").code, 0);
  const Result wale = run("stretch garter" + common +
                          " -d wale --clamp-stitches 1 --bind-off --out " + dir + "/wale");
  ASSERT_EQ(wale.code, 0) << wale.output;
  for (const char* f : {"/course/stretch.csv", "/course/relaxed.kstate", "/wale/summary.json"})
    EXPECT_TRUE(fs::exists(dir + f)) << f;
  for (const auto& [run_dir, bound] : {std::pair{"/course", false}, std::pair{"/wale", true}}) {
    std::ifstream in(dir + run_dir + "/summary.json");
    EXPECT_EQ(nlohmann::json::parse(in)["bind_off"], bound) << run_dir;
    const knit::StateFile f = knit::read_state_file(dir + run_dir + "/relaxed.kstate");
    ASSERT_TRUE(f.knit.has_value());
    EXPECT_EQ(f.knit->bind_off, bound) << run_dir;
  }
  const Result plot =
      run("stretch " + dir + "/course " + dir + "/wale --plot " + dir + "/curves.png");
  ASSERT_EQ(plot.code, 0) << plot.output;
  EXPECT_TRUE(fs::exists(dir + "/curves.png"));
  const Result bad = run("stretch garter -d diagonal --out " + dir + "/bad");
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.output.find("course, wale or bias"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(dir + "/bad"));
}

}  // namespace

namespace {

// The object commands and options refuse what they cannot do, naming it, and write nothing.
TEST(Cli, ObjectCommandsRefuseBadRequests) {
  const std::string ex = KNIT_EXAMPLES;
  const std::string dir = temp_dir("cli_objects");
  std::filesystem::create_directories(dir);
  Result r = run("mesh " + ex + "/drape_sphere.json --object nope --out " + dir + "/x.obj");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("no such object (it has ball, floor)"), std::string::npos) << r.output;
  r = run("mesh " + ex + "/drape_sphere.json --object floor --out " + dir + "/x.obj");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("unbounded"), std::string::npos) << r.output;
  r = run("mesh " + ex + "/drape_sphere.json --object ball --out " + dir + "/x.stl");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find(".obj"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.obj"));
  // a knit given on the command line needs a scene with one knit to replace
  r = run("simulate " + ex + "/pendulum.json --knit " + ex +
          "/knits/stockinette_12x12.kstate --out " + dir + "/run");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("none or several"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/run"));
  // and the good request writes a closed surface
  r = run("mesh " + ex + "/drape_sphere.json --object ball --voxel 0.3 --out " + dir + "/ball.obj");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("0 open edges"), std::string::npos) << r.output;
  std::filesystem::remove_all(dir);
}

// the sheet's options need --sheet; a bad stiffness is refused naming it; a good request
// writes the sheet's curve and summary
TEST(Cli, SheetStretchRefusesBadRequestsAndRuns) {
  const std::string knit = std::string(KNIT_EXAMPLES) + "/knits/stockinette_12x12.kstate";
  const std::string dir = temp_dir("cli_sheet");
  std::filesystem::remove_all(dir);
  Result r = run("stretch --from " + knit + " --k-shear 5 --out " + dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("need --sheet"), std::string::npos) << r.output;
  r = run("stretch --from " + knit + " --sheet --k-shear -5 --out " + dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("--k-shear"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir));
  // the held protocol, yarn friction and the load limit are the yarn model's, --hold's
  // options go with it, and the load limit is not below 0: each refused by name
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"--sheet --hold 0.05", "--hold"},
      {"--sheet --yarn-friction 0.3", "--yarn-friction"},
      {"--sheet --max-force 1e4", "--max-force"},
      {"--max-force -1", "--max-force"},
      {"--hold-time 0.2", "need --hold"}};
  for (const auto& [options, named] : refused) {
    r = run("stretch --from " + knit + " " + options + " --out " + dir);
    EXPECT_NE(r.code, 0) << options;
    EXPECT_NE(r.output.find(named), std::string::npos) << options << ": " << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(dir));
  r = run("stretch --from " + knit + " --sheet --to 0.1 --no-render -q --out " + dir);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir + "/stretch.csv"));
  std::ifstream in(dir + "/summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_EQ(s["model"], "sheet");
  EXPECT_GT(s["stretch"]["max_force_dyn"].get<double>(), 0.0);
  std::filesystem::remove_all(dir);
}

}  // namespace

namespace {

TEST(Cli, RelaxesAKnitoutProgramAtItsSizeAndRefusesWhatItCannotKnit) {
  const std::string yarns = std::string(KNIT_TEST_DATA) + "/yarns/";
  const std::string out = temp_dir("cli_knitout");
  const Result r =
      run("relax " + yarns + "swatch4x4garter.k --max-time 0.001 --quiet --out " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  const auto f = knit::read_state_file(out + "/relaxed.kstate");
  ASSERT_TRUE(f.knit.has_value());
  EXPECT_EQ(f.knit->rows, 4);
  EXPECT_EQ(f.knit->cols, 4);
  EXPECT_FALSE(f.knit->in_the_round);
  // another size than the program's
  const std::string out2 = temp_dir("cli_knitout_size");
  const Result size = run("relax " + yarns + "swatch4x4.k --cols 6 --out " + out2);
  EXPECT_EQ(size.code, 1);
  EXPECT_NE(size.output.find("the program knits 4 rows × 4 columns flat"), std::string::npos)
      << size.output;
  EXPECT_FALSE(fs::exists(out2));
  // a decrease (two loops moved onto one needle and knit together)
  const std::string prog = ::testing::TempDir() + "/cli_xfer.k";
  std::ofstream(prog) << ";!knitout-2\nin 3\nknit + f1 3\nknit + f2 3\nxfer f2 b2\nrack -1\n"
                         "xfer b2 f1\nrack 0\nknit - f1 3\n";
  const Result xfer = run("relax " + prog + " --out " + out2);
  EXPECT_EQ(xfer.code, 1);
  EXPECT_NE(xfer.output.find("cli_xfer.k:9: 'knit - f1 3': a decrease (2 loops"), std::string::npos)
      << xfer.output;
  EXPECT_FALSE(fs::exists(out2));
}

}  // namespace

namespace {

TEST(Cli, ViewWritesAPageForARunAndRefusesAnotherName) {
  const std::string out = temp_dir("cli_view_run");
  ASSERT_EQ(run(std::string("simulate ") + KNIT_EXAMPLES +
                "/pendulum.json --duration 0.05 --quiet --out " + out)
                .code,
            0);
  const Result r = run("view " + out + " --every 2 --out " + out + "/run.html");
  ASSERT_EQ(r.code, 0) << r.output;
  // frames 0, 2, 4 and the last of the 6 written
  EXPECT_NE(r.output.find("(4 frames"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(out + "/run.html"));
  const Result bad = run("view " + out + " --out " + out + "/run.png");
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.output.find("name it .html"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(out + "/run.png"));
}

// the objects of the page's data (viewer.hpp), by name
std::vector<std::string> page_objects(const std::string& page) {
  std::ifstream in(page);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string html = ss.str(), open = "id=\"knitsim-data\">";
  const size_t begin = html.find(open) + open.size();
  const auto d = nlohmann::json::parse(html.substr(begin, html.find("</script>", begin) - begin));
  std::vector<std::string> names;
  for (const auto& o : d["objects"]) names.push_back(o["name"]);
  return names;
}

// view draws a run's objects as render does: those of the scene its summary.json names, or
// of --scene; --no-objects leaves them out
TEST(Cli, ViewDrawsTheScenesObjects) {
  const std::string out = temp_dir("cli_view_objects");
  fs::create_directories(out);
  const std::string scene = out + "/ball.json";
  std::ofstream(scene)
      << R"({"yarns": [{"line": {"from": [-2,0,1.2], "to": [2,0,1.2], "segments": 8}}],
    "objects": [{"name": "ball", "sphere": {"center": [0,0,0], "radius": 1}},
                {"name": "floor", "plane": {"point": [0,0,-1], "normal": [0,0,1]}}],
    "time_step": 0.0001, "duration": 0.002, "output_every": 10})";
  ASSERT_EQ(run("simulate " + scene + " --quiet --out " + out + "/run").code, 0);
  Result r = run("view " + out + "/run --out " + out + "/run.html");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("with the objects of " + scene), std::string::npos) << r.output;
  EXPECT_EQ(page_objects(out + "/run.html"), (std::vector<std::string>{"ball", "floor"}));
  r = run("view " + out + "/run --no-objects --out " + out + "/alone.html");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(page_objects(out + "/alone.html").empty());
  const std::string ex = KNIT_EXAMPLES;
  r = run("view " + ex + "/knits/stockinette_12x12.kstate --scene " + ex +
          "/drape_sphere.json --out " + out + "/drape.html");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(page_objects(out + "/drape.html"), (std::vector<std::string>{"ball", "floor"}));
  fs::remove_all(out);
}

}  // namespace
