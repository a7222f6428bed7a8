// A run interrupted at any step and resumed in its directory leaves the uninterrupted run's
// log (runner.hpp): every row, none twice, whatever the rounding of a row's time as the log
// writes it; and a signal that comes during the last step leaves a finished run, not one
// to resume with no time left.
#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "knit/io/state_file.hpp"
#include "knit/run/interrupt.hpp"
#include "knit/run/runner.hpp"
#include "yarn_setups.hpp"

namespace knit {
namespace {

namespace fs = std::filesystem;
using test::line;

// the relaxation step (1/11800 s): many of its multiples, written with the log's 10
// digits, round above the time the state holds
constexpr double STEP = 1.0 / 11800;
constexpr int STEPS = 24;

// a free yarn 5 % too long, pulled back by its length energy
Model short_run_model(State& s) {
  ModelBuilder b;
  b.add_yarn(line(8, 4.0));
  Params p = Params::relaxation();
  p.gravity.setZero();
  p.material.k_len = 1e3;
  p.material.contact = false;
  p.solver.time_step = STEP;
  Model m = b.build(p, 1 / 1.05);
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  return m;
}

RunOptions options(const std::string& dir, int output_every) {
  RunOptions o;
  o.end_time = STEPS * STEP;
  o.output_every = output_every;
  o.progress = false;
  o.write_frames = false;
  o.checkpoint_every_s = 0;
  o.out_dir = dir;
  return o;
}

// the log's rows without the wall seconds per step (the one column a leg may change)
std::vector<std::string> log_rows(const std::string& dir) {
  std::ifstream in(dir + "/log.csv");
  std::vector<std::string> rows;
  for (std::string l; std::getline(in, l);) {
    std::vector<std::string> cells;
    std::stringstream ss(l);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    std::string row;
    for (size_t i = 0; i < cells.size(); ++i)
      if (i != 6) row += cells[i] + ",";
    rows.push_back(row);
  }
  return rows;
}

// runs to the end, interrupted after the `stop_after`th output (when > 0); returns its status
StepStatus run_once(const std::string& dir, int output_every, int stop_after, bool resume) {
  State s;
  Model m = short_run_model(s);
  RunOptions o = options(dir, output_every);
  if (resume) {
    const StateFile f = read_state_file(dir + "/final.kstate");
    s = f.state;
    o.continue_in_place = true;
    o.resumed_totals = f.run;
  }
  int outputs = 0;
  if (stop_after > 0)
    o.on_output = [&](const StepData&, const State&) {
      if (++outputs == stop_after) request_interrupt(SIGINT);
    };
  Simulator sim(m);
  InterruptHandler handler;
  const RunReport r = run_simulation(sim, s, o);
  clear_interrupt();
  EXPECT_TRUE(r.status == StepStatus::OK || r.status == StepStatus::INTERRUPTED) << r.message;
  return r.status;
}

TEST(RunnerResume, ALogResumedAfterAnyStepHasTheUninterruptedRunsRows) {
  const std::string whole = ::testing::TempDir() + "/runner_resume_whole",
                    cut = ::testing::TempDir() + "/runner_resume_cut";
  int rounded_up = 0;  // interrupts whose state's time the log wrote above it
  for (int every : {1, 3}) {
    fs::remove_all(whole);
    ASSERT_EQ(run_once(whole, every, 0, false), StepStatus::OK);
    const std::vector<std::string> expected = log_rows(whole);
    ASSERT_GT(expected.size(), 3u);
    // interrupted one step after each output (at an output step where every = 1, between
    // two elsewhere), then resumed to the end
    for (int stop = 1; stop * every < STEPS - 1; ++stop) {
      fs::remove_all(cut);
      ASSERT_EQ(run_once(cut, every, stop, false), StepStatus::INTERRUPTED) << stop;
      const double t = read_state_file(cut + "/final.kstate").state.time;
      char text[32];
      std::snprintf(text, sizeof text, "%.10g", t);
      if (std::strtod(text, nullptr) > t * (1 + 1e-12) + 1e-15 &&
          std::lround(t / STEP) % every == 0)
        ++rounded_up;
      ASSERT_EQ(run_once(cut, every, 0, true), StepStatus::OK) << stop;
      EXPECT_EQ(log_rows(cut), expected)
          << "interrupted at t = " << text << " s (" << every << " steps an output)";
    }
  }
  EXPECT_GT(rounded_up, 0) << "no interrupt at a time the log rounds up: the test would not "
                              "see a row dropped for it";
}

TEST(RunnerResume, ASignalDuringTheLastStepLeavesAFinishedRun) {
  const std::string dir = ::testing::TempDir() + "/runner_last_step";
  fs::remove_all(dir);
  // the signal comes at the output before the last step: the last step reads it
  EXPECT_EQ(run_once(dir, 1, STEPS, false), StepStatus::OK);
  std::ifstream in(dir + "/summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  EXPECT_EQ(s["status"], "ok");
  EXPECT_FALSE(s.contains("resume_command")) << s.dump(2);
  EXPECT_NEAR(s["sim_time_s"].get<double>(), STEPS * STEP, 1e-12);
}

}  // namespace
}  // namespace knit
