// StepData: what a step records is what a fresh evaluation finds, logging reads it without
// evaluating anything, and the contact set agrees with the contact term's point pairs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "knit/contact/contact_term.hpp"
#include "knit/recipes/relax_knit.hpp"
#include "knit/run/runner.hpp"
#include "knit/scene/scene.hpp"

namespace knit {
namespace {

Scene example(const char* name) {
  return load_scene(std::string(KNIT_EXAMPLES) + "/" + name);
}

// a 6×6 stockinette as relax_knit sets it up, under gravity: many yarn pieces in contact
KnitRelaxation swatch() {
  RelaxKnitOptions o;
  o.knit.rows = 6;
  o.knit.cols = 6;
  o.params.gravity = Eigen::Vector3d(0, 0, -981);
  return setup_knit_relaxation("stockinette", o);
}

long long contact_evaluations(const Simulator& sim) {
  for (const auto& t : sim.terms())
    if (t->name() == "contact") return t->evaluations();
  ADD_FAILURE() << "no contact term";
  return -1;
}

// the contact term is evaluated the same number of times whether the run logs and writes
// a state every step or once: logging never evaluates a term
TEST(StepData, LoggingEveryStepEvaluatesNothing) {
  long long evaluations[2];
  for (int k = 0; k < 2; ++k) {
    Scene scene = example("drop_on_yarn.json");
    Simulator sim(scene.model);
    RunOptions o;
    o.duration = 60 * scene.model.params.solver.time_step;
    o.output_every = k == 0 ? 1 : 1000;
    o.out_dir =
        (std::filesystem::path(::testing::TempDir()) / ("step_data_log" + std::to_string(k)))
            .string();
    std::filesystem::remove_all(o.out_dir);
    o.progress = false;
    const RunReport r = run_simulation(sim, scene.state, o);
    ASSERT_EQ(r.steps, 60);
    evaluations[k] = contact_evaluations(sim);
  }
  EXPECT_EQ(evaluations[0], evaluations[1]);
  // one evaluation at the start, then two per step (the second of each step's pair is at
  // its result, reused by the next step)
  EXPECT_EQ(evaluations[0], 1 + 2 * 60);
}

// A run whose steps keep lean records (the runner's setting with the IMEX step and no
// explicit term that reads the velocities: Simulator::set_lean_records) still logs whole
// ones: every row's energies finite, the potential energy their sum; the simulator's
// setting is as before once the run ends, and its records whole.
TEST(StepData, LeanStepsLogWholeRecords) {
  RelaxKnitOptions o;
  o.knit.rows = 6;
  o.knit.cols = 6;
  o.params.solver.integrator = Integrator::IMEX_CONTACT;
  o.params.solver.contact_reuse = 0.05;
  o.params.solver.time_step = 6e-4;
  o.params.material.k_global = 0;
  KnitRelaxation setup = setup_knit_relaxation("stockinette", o);
  Simulator& sim = *setup.sim;
  RunOptions r;
  r.duration = 30 * 6e-4;
  r.output_every = 7;
  r.out_dir = (std::filesystem::path(::testing::TempDir()) / "step_data_lean").string();
  std::filesystem::remove_all(r.out_dir);
  r.progress = false;
  ASSERT_FALSE(sim.lean_records());
  const RunReport report = run_simulation(sim, setup.state, r);
  ASSERT_EQ(report.status, StepStatus::OK) << report.message;
  EXPECT_FALSE(sim.lean_records());
  EXPECT_TRUE(std::isfinite(sim.data().potential_energy));
  std::ifstream log(std::filesystem::path(r.out_dir) / "log.csv");
  std::string line;
  ASSERT_TRUE(std::getline(log, line));
  auto split = [](const std::string& text) {
    std::vector<std::string> cells;
    std::stringstream in(text);
    for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
    return cells;
  };
  const std::vector<std::string> header = split(line);
  int rows = 0;
  while (std::getline(log, line)) {
    const std::vector<std::string> cells = split(line);
    ASSERT_EQ(cells.size(), header.size());
    double potential = 0, sum = 0;
    bool bending = false;
    for (size_t c = 0; c < header.size(); ++c) {
      if (header[c] == "potential_energy") potential = std::stod(cells[c]);
      if (header[c].rfind("energy_", 0) != 0) continue;
      const double e = std::stod(cells[c]);
      EXPECT_TRUE(std::isfinite(e)) << header[c] << " in row " << rows;
      sum += e;
      bending = bending || header[c] == "energy_bending";
    }
    EXPECT_TRUE(bending);
    EXPECT_NEAR(potential, sum, 1e-8 * std::abs(sum)) << "row " << rows;
    ++rows;
  }
  EXPECT_EQ(rows, 1 + 30 / 7 + 1);  // the start, every 7th step, the last
}

TEST(StepData, RecordsWhatAFreshEvaluationFinds) {
  KnitRelaxation setup = swatch();
  Simulator& sim = *setup.sim;
  State& s = setup.state;
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(sim.step(s).ok());
  const StepData& d = sim.data();
  EXPECT_EQ(d.steps, 100);
  EXPECT_DOUBLE_EQ(d.time, s.time);
  EXPECT_DOUBLE_EQ(d.kinetic_energy, sim.kinetic_energy(s));
  double sum = 0;
  for (const TermRecord& t : d.terms) sum += t.energy;
  EXPECT_DOUBLE_EQ(d.potential_energy, sum);
  EXPECT_NEAR(d.potential_energy, sim.potential_energy(s), 1e-9 * std::abs(d.potential_energy));
  EXPECT_NEAR(d.max_violation, sim.max_violation(s), 1e-15);
  // gravity's net force is the weight
  const TermRecord* g = d.term("gravity");
  ASSERT_NE(g, nullptr);
  const Eigen::Vector3d weight = sim.model().mass.sum() * sim.model().params.gravity;
  EXPECT_LT((g->net_force - weight).norm(), 1e-9 * weight.norm());
  // the internal energies exert no net force
  for (const char* name : {"bending", "length"})
    EXPECT_LT(d.term(name)->net_force.norm(), 1e-9 * weight.norm()) << name;
  ASSERT_TRUE(d.contact.present);
  EXPECT_GT(d.contact.point_pairs_in_contact, 100);
  EXPECT_TRUE(d.projection.converged);
  ASSERT_EQ(d.constraints.size(), 2u);  // the knit's two glues (no length rows in relaxation)
  EXPECT_EQ(d.constraints[0].kind, "glue");
  EXPECT_GT(d.stage_seconds.count("contact"), 0u);
  EXPECT_GT(d.stage_seconds.count("projection"), 0u);
}

// the segment pairs of the contact set are exactly those with a point pair in contact
// (from the term's own point-pair records), each with its closest distance, a unit normal
// and, for yarns pressed together at rest, a repulsive normal force
TEST(StepData, ContactSetMatchesThePointPairs) {
  KnitRelaxation setup = swatch();
  Simulator& sim = *setup.sim;
  State& state = setup.state;
  ContactTerm* term = nullptr;  // the oracle: the term's own point-pair records
  for (const auto& t : sim.terms())
    if (t->name() == "contact") term = static_cast<ContactTerm*>(t.get());
  ASSERT_NE(term, nullptr);
  for (int i = 0; i < 50; ++i) ASSERT_TRUE(sim.step(state).ok());
  term->set_record_point_pairs(true);
  State probe = state;
  probe.time += 1e-9;  // a state the simulator has not recorded: forward evaluates it
  sim.forward(probe);
  const Model& model = sim.model();
  std::set<std::pair<int, int>> want;
  for (const ContactPointPair& p : term->last_point_pairs()) want.insert({p.seg_i, p.seg_j});
  const ContactRecord& c = sim.data().contact;
  ASSERT_FALSE(want.empty());
  std::set<std::pair<int, int>> got;
  double min_d = 1e300, total_normal = 0;
  const double two_r = 2 * model.params.material.radius;
  for (const ContactPairRecord& p : c.pairs) {
    got.insert({p.seg_i, p.seg_j});
    EXPECT_LT(p.seg_i, p.seg_j);
    EXPECT_GT(p.d, 0.0);
    EXPECT_LT(p.d, 1.0);
    EXPECT_NEAR(p.normal.norm(), 1.0, 1e-12);
    min_d = std::min(min_d, p.d);
    total_normal += p.normal_force;
    // the closest point pair's distance, found by brute force over the contact points
    double best = 1e300;
    const QuadratureTable& quad = model.contact_quad;
    const Vector12d xi = gather_segment(probe.q, model.seg_cp[p.seg_i]);
    const Vector12d xj = gather_segment(probe.q, model.seg_cp[p.seg_j]);
    for (int a = 0; a < quad.size(); ++a)
      for (int b = 0; b < quad.size(); ++b)
        best = std::min(best, (combine(xj, quad.b[b]) - combine(xi, quad.b[a])).norm() / two_r);
    EXPECT_NEAR(p.d, best, 1e-12);
    // and the pair is found at its curve parameters
    const Eigen::Vector3d delta =
        combine(xj, bspline_basis(p.t_j)) - combine(xi, bspline_basis(p.t_i));
    EXPECT_NEAR(delta.norm() / two_r, p.d, 1e-12);
    EXPECT_NEAR((delta.normalized() - p.normal).norm(), 0.0, 1e-9);
  }
  EXPECT_EQ(got, want);
  EXPECT_DOUBLE_EQ(min_d, c.min_distance_ratio);
  EXPECT_GT(total_normal, 0.0) << "contact pushes the yarn pieces apart";
}

}  // namespace
}  // namespace knit

namespace knit {
namespace {

// a step that needed more than half the projection's iterations says so; the summary
// counts the steps with each warning
TEST(StepData, WarningsReachTheSummary) {
  Scene scene = parse_scene(nlohmann::json::parse(R"({
      "params": {"max_projection_iterations": 3, "constraint_tolerance": 1e-12},
      "time_step": 0.0001, "duration": 0.01,
      "yarns": [{"line": {"from": [0, 0, 0], "to": [10, 0, 0], "segments": 20}}],
      "pins": [{"yarn": 0, "at": "start"}]})"),
                            "pendulum.json");
  Simulator sim(scene.model);
  RunOptions o;
  o.duration = scene.duration;
  o.progress = false;
  const RunReport r = run_simulation(sim, scene.state, o);
  ASSERT_EQ(r.summary["status"], "ok") << r.summary.dump(2);
  ASSERT_TRUE(r.summary.contains("warnings")) << r.summary.dump(2);
  const auto& w = r.summary["warnings"];
  ASSERT_TRUE(w.contains("the projection needed more than half its iterations")) << w.dump();
  EXPECT_GT(w["the projection needed more than half its iterations"].get<int>(), 0);
  EXPECT_LE(w["the projection needed more than half its iterations"].get<int>(), r.steps);
}

}  // namespace
}  // namespace knit
