// Steps taken again in halves (solver/step_halving.hpp): a step too long for the yarn's
// stiffness fails, is taken again as 2ᵏ shorter ones, and the run reaches the same rest a
// short step reaches; where even h/2ⁿ fails the run stops and says how far it halved.
#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <filesystem>

#include "knit/constraints/projection.hpp"
#include "knit/io/state_file.hpp"
#include "knit/run/interrupt.hpp"
#include "knit/run/runner.hpp"
#include "knit/run/step_halving.hpp"
#include "yarn_setups.hpp"

namespace knit {
namespace {

using test::line;

// A free, weightless yarn made 5 % longer than its rest length, pulled back to it by a
// stiff length energy (no length constraints) and brought to rest by global damping.
constexpr double K_LEN = 1e4;
constexpr double LONG_STEP = 4e-4;  // fails within a few steps (measured: see below)

Model stretched_yarn(State& s, int halvings) {
  ModelBuilder b;
  b.add_yarn(line(10, 5.0));
  Params p = Params::relaxation();
  p.gravity.setZero();
  p.material.k_len = K_LEN;
  p.material.k_global = 20;
  p.material.contact = false;
  p.solver.max_step_halvings = halvings;
  Model m = b.build(p, 1 / 1.05);
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  return m;
}

TEST(StepHalving, AStepTooLongForTheYarnIsTakenInHalvesAndReachesTheRest) {
  // the plain step of LONG_STEP fails: the length energy's stiffness bounds it
  {
    State s;
    Simulator sim(stretched_yarn(s, 0));
    StepResult r;
    for (int i = 0; i < 200 && r.ok(); ++i) r = sim.step(s, LONG_STEP);
    ASSERT_FALSE(r.ok()) << "LONG_STEP no longer fails: the test needs a longer one";
  }
  // in halves it runs on, and the yarn comes to its rest length, as with a short step
  State s;
  Simulator sim(stretched_yarn(s, 4));
  HalvingStepper stepper(4, 0);
  const double duration = 0.4;
  const int steps = static_cast<int>(std::lround(duration / LONG_STEP));
  for (int i = 0; i < steps; ++i) {
    const StepResult r = stepper.step(sim, s, LONG_STEP);
    ASSERT_TRUE(r.ok()) << "step " << i << ": " << r.message;
  }
  EXPECT_NEAR(s.time, duration, 1e-9);
  EXPECT_GT(stepper.retried(), 0);
  EXPECT_GE(stepper.deepest(), 1);
  EXPECT_LE(stepper.deepest(), 4);
  EXPECT_GT(stepper.substeps(), steps);
  EXPECT_EQ(stepper.level(), stepper.deepest());  // calm_steps 0: the halved step stays
  // at rest every segment has its rest length again: the length residual C = |Δ|/l − 1
  const double violation = FastProjection::max_length_violation(sim.model(), s.q);
  EXPECT_LT(violation, 1e-3);

  State fine;
  Simulator reference(stretched_yarn(fine, 0));
  const double h = std::ldexp(LONG_STEP, -stepper.deepest());
  for (int i = 0; i < std::lround(duration / h); ++i) ASSERT_TRUE(reference.step(fine, h).ok());
  EXPECT_LT(FastProjection::max_length_violation(reference.model(), fine.q), 1e-3);
  // the same rest (free in space, it may have drifted: compare shapes, centred)
  const Eigen::Map<const Eigen::Matrix3Xd> a(s.q.data(), 3, s.q.size() / 3),
      b(fine.q.data(), 3, fine.q.size() / 3);
  const Eigen::Matrix3Xd da = a.colwise() - a.rowwise().mean(),
                         db = b.colwise() - b.rowwise().mean();
  EXPECT_LT((da - db).cwiseAbs().maxCoeff(), 1e-3) << "cm";
}

// Where h/2ⁿ fails too, the run stops with the last good state and says how far it halved.
TEST(StepHalving, WhereEvenTheHalvedStepFailsTheRunSaysSo) {
  State s;
  Model m = stretched_yarn(s, 1);
  m.params.material.k_len = 1e9;  // far beyond what LONG_STEP / 2 holds
  m.params.solver.time_step = LONG_STEP;
  Simulator sim(std::move(m));
  RunOptions o;
  o.duration = 0.1;
  o.progress = false;
  const RunReport r = run_simulation(sim, s, o);
  ASSERT_NE(r.status, StepStatus::OK);
  EXPECT_NE(r.message.find("halved 1 time, to 0.0002 s"), std::string::npos) << r.message;
  EXPECT_TRUE(s.finite());
  const auto& h = r.summary["step_halvings"];
  EXPECT_GE(h["retried"].get<long long>(), 1) << h.dump();
  EXPECT_EQ(h["deepest"].get<int>(), 1) << h.dump();
  EXPECT_EQ(r.summary["params"]["solver"]["max_step_halvings"].get<int>(), 1);
}

// A run interrupted while its step was halved goes on at that halving when resumed in its
// directory (the state's run totals say where the stepper stood): it ends as the
// uninterrupted run, its state, totals and summary's halvings alike.
TEST(StepHalving, ARunResumedWhileHalvedGoesOnAtItsHalvedStep) {
  namespace fs = std::filesystem;
  auto options = [](const std::string& dir) {
    RunOptions o;
    o.end_time = 0.08;
    o.output_every = 10;
    o.progress = false;
    o.halving_calm_steps = 50;  // halved for a while, then doubled again
    o.out_dir = dir;
    return o;
  };
  auto model = [] {
    State s;
    Model m = stretched_yarn(s, 4);
    m.params.solver.time_step = LONG_STEP;
    return std::pair{std::move(m), s};
  };
  const std::string whole = ::testing::TempDir() + "/halving_whole",
                    cut = ::testing::TempDir() + "/halving_cut";
  fs::remove_all(whole);
  fs::remove_all(cut);
  auto [m, s] = model();
  Simulator sim(m);
  const RunReport a = run_simulation(sim, s, options(whole));
  ASSERT_EQ(a.status, StepStatus::OK) << a.message;
  ASSERT_GT(a.summary["step_halvings"]["retried"].get<long long>(), 0);

  // interrupted one step after its output at step 20, between two output steps
  {
    auto [m2, s2] = model();
    Simulator sim2(m2);
    InterruptHandler handler;
    RunOptions o = options(cut);
    int outputs = 0;
    o.on_output = [&](const StepData&, const State&) {
      if (++outputs == 3) request_interrupt(SIGINT);
    };
    const RunReport r = run_simulation(sim2, s2, o);
    clear_interrupt();
    ASSERT_EQ(r.status, StepStatus::INTERRUPTED);
  }
  StateFile f = read_state_file(cut + "/final.kstate");
  ASSERT_TRUE(f.run.has_value());
  ASSERT_GT(f.run->halving.level, 0) << "the test needs a run interrupted while halved";
  EXPECT_NE(std::lround(f.state.time / LONG_STEP) % 10, 0) << "between two output steps";
  auto [m3, unused] = model();
  Simulator sim3(m3);
  RunOptions o = options(cut);
  o.continue_in_place = true;
  o.resumed_totals = f.run;
  const RunReport b = run_simulation(sim3, f.state, o);
  ASSERT_EQ(b.status, StepStatus::OK) << b.message;
  EXPECT_EQ(b.summary["step_halvings"], a.summary["step_halvings"]);
  EXPECT_EQ(b.summary["steps"], a.summary["steps"]);
  const StateFile x = read_state_file(whole + "/final.kstate"),
                  y = read_state_file(cut + "/final.kstate");
  EXPECT_TRUE(x.state.q == y.state.q) << "positions differ after the resume";
  EXPECT_TRUE(x.state.v == y.state.v) << "velocities differ after the resume";
  ASSERT_TRUE(x.run && y.run);
  EXPECT_EQ(to_json(*x.run), to_json(*y.run));
}

}  // namespace
}  // namespace knit
