// Scenes place a relaxed knit read from a .kstate and clamp it by stitch coordinates.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "knit/constraints/groups.hpp"
#include "knit/io/state_file.hpp"
#include "knit/recipes/relax_knit.hpp"
#include "knit/recipes/simulate_scene.hpp"
#include "knit/scene/scene.hpp"

namespace knit {
namespace {

namespace fs = std::filesystem;

// a 4×5 stockinette relaxed for a few steps, written as `knitsim relax` writes it
struct KnitFile {
  KnitFile() {
    RelaxKnitOptions o;
    o.knit.rows = 4;
    o.knit.cols = 5;
    o.run.max_time = 30 * o.params.solver.time_step;
    o.run.progress = false;
    const RelaxResult r = relax_knit("stockinette", o);
    model = std::make_unique<Model>(r.model);
    state = r.state;
    path = (fs::path(::testing::TempDir()) / "scene_knit.kstate").string();
    write_state_file(path, make_state_file(*model, state));
  }
  std::unique_ptr<Model> model;
  State state;
  std::string path;
};

Scene parse(const std::string& text) {
  const std::string scene_path = (fs::path(::testing::TempDir()) / "scene_knit.json").string();
  return parse_scene(nlohmann::json::parse(text), scene_path);
}

std::string message_of(const std::string& text) {
  try {
    parse(text);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(SceneKnit, PlacedAtRestWithItsStitchesAndGlues) {
  const KnitFile f;
  const Scene scene = parse(R"({"knits": [{"state": "scene_knit.kstate", "translate": [1, 2, 3],
                                           "rotate": {"axis": [1, 0, 0], "degrees": 90}}],
                               "clamps": [{"name": "top", "rows": [-1, -1]}]})");
  const Model& m = scene.model;
  ASSERT_EQ(m.num_seg(), f.model->num_seg());
  // rotated 90° about x, then translated: (x, y, z) → (x + 1, −z + 2, y + 3)
  for (int k = 0; k < m.num_cp(); k += 7) {
    const Eigen::Vector3d p = f.state.q.segment<3>(3 * k);
    EXPECT_LT((scene.state.q.segment<3>(3 * k) - Eigen::Vector3d(p.x() + 1, -p.z() + 2, p.y() + 3))
                  .norm(),
              1e-12);
  }
  EXPECT_EQ(scene.state.v.norm(), 0.0);
  // the simulation parameters, the knit's stitches and its glues, closed
  EXPECT_EQ(m.params.material.k_bend, Params::simulation().material.k_bend);
  EXPECT_TRUE(m.params.solver.length_constraints);
  for (int i = 0; i < m.num_seg(); ++i) EXPECT_EQ(m.stitch[i].row, f.model->stitch[i].row);
  ASSERT_EQ(m.glues.size(), f.model->glues.size());
  for (const Glue& g : m.glues)  // held at their placed separation
    EXPECT_LT((point_position(m, scene.state.q, g.a) - point_position(m, scene.state.q, g.b) -
               g.offset(1.0))
                  .norm(),
              1e-12);
  // rest lengths are the placed yarn's own: the length constraints hold from the start
  EXPECT_LT(FastProjection::max_length_violation(m, scene.state.q), 1e-12);
  // the top row's segments, one point each
  ASSERT_EQ(m.clamps.size(), 1u);
  std::set<int> top;
  for (int i = 0; i < m.num_seg(); ++i)
    if (m.stitch[i].row == 3)
      for (int a = 0; a < 4; ++a) top.insert(m.seg_cp[i] + a);
  EXPECT_TRUE(m.clamps[0].points.empty());
  EXPECT_EQ(std::set<int>(m.clamps[0].control_points.begin(), m.clamps[0].control_points.end()),
            top);
  // the clamp fixes the top row's shape: those segments' length rows are left out
  int held_segments = 0;
  for (int i = 0; i < m.num_seg(); ++i) {
    bool all = true;
    for (int a = 0; a < 4; ++a) all = all && top.count(m.seg_cp[i] + a);
    held_segments += all;
  }
  ASSERT_GT(held_segments, 0);
  const Model groups = with_constraint_groups(m);
  EXPECT_EQ(groups.constraint_groups[0]->name(), "length");
  EXPECT_EQ(groups.constraint_groups[0]->rows(), m.num_seg() - held_segments);
  ASSERT_EQ(scene.knits.size(), 1u);
  EXPECT_FALSE(scene.knits[0].in_the_round);
}

TEST(SceneKnit, HangsFromItsClampAndReportsTheForce) {
  const KnitFile f;
  Scene scene = parse(R"({"knits": [{"state": "scene_knit.kstate"}], "duration": 0.004,
                          "clamps": [{"name": "top", "rows": [-1, -1]}]})");
  SimulateOptions o;
  o.progress = false;
  const RunReport r = simulate_scene(scene, o);  // no out_dir: nothing written
  ASSERT_EQ(r.summary["status"], "ok") << r.summary.dump(2);
  ASSERT_TRUE(r.summary["constraint_forces"].contains("top"));
  EXPECT_EQ(r.summary["constraint_forces"]["top"]["kind"], "clamp");
  // the knit starts falling: the clamp pulls up
  EXPECT_GT(r.summary["constraint_forces"]["top"]["force"][2].get<double>(), 0.0);
  EXPECT_EQ(r.summary["knits"].size(), 1u);
}

TEST(SceneKnit, BadKnitsAndClampsAreNamed) {
  const KnitFile f;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"knits": [{"state": "missing.kstate"}]})", "knits[0].state"},
      {R"({"knits": [{"state": "scene_knit.kstate"}, {"state": "scene_knit.kstate"}]})",
       "at most one knit"},
      {R"({"knits": [{"state": "scene_knit.kstate", "scale": 2}]})", "scale"},
      {R"({"knits": [{"state": "scene_knit.kstate", "rotate": {"axis": [0,0,0], "degrees": 3}}]})",
       "knits[0].rotate.axis"},
      {R"({"knits": [{"state": "scene_knit.kstate"}], "clamps": [{"rows": [0, 9]}]})",
       "clamps[0].rows"},
      {R"({"knits": [{"state": "scene_knit.kstate"}], "clamps": [{"rows": [0, 1], "points": []}]})",
       "or \"points\""},
      {R"({"yarns": [{"line": {"from": [0,0,0], "to": [1,0,0], "segments": 4}}],
           "clamps": [{"cols": [0, 1]}]})",
       "no knit"},
      {R"({"knits": [{"state": "scene_knit.kstate"}],
           "clamps": [{"name": "a", "rows": [0, 0]}, {"name": "a", "rows": [1, 1]}]})",
       "two clamps"},
      {R"({"knits": [{"state": "scene_knit.kstate"}],
           "clamps": [{"rows": [0, 0], "keyframes": [{"time": 1}, {"time": 0.5}]}]})",
       "keyframes[1].time"},
      {R"({"yarns": [{"line": {"from": [0,0,0], "to": [1,0,0], "segments": 4}}],
           "params": {"alpha_large": 0.5}})",
       "params.alpha_large: the non-rigid damping acts on a placed knit"},
  };
  for (const auto& [text, expected] : cases) {
    const std::string msg = message_of(text);
    EXPECT_NE(msg.find(expected), std::string::npos) << "'" << expected << "' not in: " << msg;
  }
  // a state without stitch coordinates is not a knit
  const std::string plain = (fs::path(::testing::TempDir()) / "plain.kstate").string();
  ModelBuilder b;
  Eigen::Matrix3Xd cp(3, 6);
  for (int k = 0; k < 6; ++k) cp.col(k) = Eigen::Vector3d(k, 0, 0);
  b.add_yarn(cp);
  State s;
  s.q = b.positions();
  s.v = Eigen::VectorXd::Zero(s.q.size());
  write_state_file(plain, make_state_file(b.build(Params{}), s));
  EXPECT_NE(message_of(R"({"knits": [{"state": "plain.kstate"}]})").find("no stitch coordinates"),
            std::string::npos);
}

}  // namespace
}  // namespace knit

namespace knit {
namespace {

// A knit stretched between two clamps: the bottom row held, the top row pulled up and
// turned. Every other force on the yarn is internal (bending, length, contact and its
// damping, glue and length rows) or conserves momentum (the non-rigid damping keeps each
// region's momentum), so each step changes the momentum by exactly h · (M g + the two
// clamp forces) — Newton's second law for the whole sample, to round-off.
TEST(SceneKnit, StretchedSampleObeysNewtonsSecondLaw) {
  const KnitFile f;
  Scene scene = parse(R"({"knits": [{"state": "scene_knit.kstate"}],
      "clamps": [{"name": "bottom", "rows": [0, 0]},
                 {"name": "top", "rows": [-1, -1],
                  "keyframes": [{"time": 0}, {"time": 0.02, "translate": [0, 0.3, 0.1],
                                              "rotate": {"axis": [0, 1, 0], "degrees": 5}}]}]})");
  auto sim = make_scene_simulator(scene);
  const Model& m = sim->model();
  const double h = m.params.solver.time_step;
  const Eigen::Vector3d weight = m.mass.sum() * m.params.gravity;
  double worst = 0, scale = 0;
  for (int i = 0; i < 300; ++i) {  // 0.025 s: pulled, then held
    const Eigen::Vector3d p0 = sim->linear_momentum(scene.state);
    const StepResult r = sim->step(scene.state);
    ASSERT_TRUE(r.ok()) << i << ": " << r.message;
    const Eigen::Vector3d dp = sim->linear_momentum(scene.state) - p0;
    const Eigen::Vector3d f =
        weight + sim->data().constraint("bottom")->force + sim->data().constraint("top")->force;
    worst = std::max(worst, (dp / h - f).norm());
    scale = std::max(scale, sim->data().constraint("top")->force.norm());
  }
  ASSERT_GT(scale, weight.norm()) << "the pulled clamp should carry more than the weight";
  EXPECT_LT(worst, 1e-8 * scale) << "largest |Δp/h − ΣF|, against max |F_top| = " << scale;
}

}  // namespace
}  // namespace knit

namespace knit {
namespace {

// "rows" and "cols" together hold the stitches in both ranges: a corner
TEST(SceneKnit, ClampByRowsAndColumnsHoldsACorner) {
  const KnitFile f;
  const Scene scene = parse(R"({"knits": [{"state": "scene_knit.kstate"}],
                               "clamps": [{"rows": [-2, -1], "cols": [-2, -1]}]})");
  const Model& m = scene.model;
  std::set<int> want;
  for (int i = 0; i < m.num_seg(); ++i)
    if (m.stitch[i].row >= 2 && m.stitch[i].col >= 3)
      for (int a = 0; a < 4; ++a) want.insert(m.seg_cp[i] + a);
  ASSERT_FALSE(want.empty());
  const auto& got = m.clamps[0].control_points;
  EXPECT_EQ(std::set<int>(got.begin(), got.end()), want);
}

}  // namespace
}  // namespace knit
