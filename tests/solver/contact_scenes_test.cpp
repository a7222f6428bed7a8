// The contact example scenes run through the whole simulator: yarns never pass through
// each other, lengths hold, and no yarn moves far enough in one step to tunnel.
#include <gtest/gtest.h>

#include "knit/scene/scene.hpp"
#include "knit/solver/simulator.hpp"

namespace knit {
namespace {

struct SceneRun {
  double min_d = 1e300;
  double max_step_travel_cm = 0;  // largest control-point displacement in one step
  double max_length_violation = 0;
  long long contact_steps = 0;
};

SceneRun run_scene(const std::string& name, double duration) {
  Scene scene = load_scene(std::string(KNIT_EXAMPLES) + "/" + name);
  Simulator sim(scene.model);
  const StepData& data = sim.data();
  SceneRun r;
  const double h = scene.model.params.solver.time_step;
  const int steps = static_cast<int>(std::lround(duration / h));
  for (int i = 0; i < steps; ++i) {
    const Eigen::VectorXd before = scene.state.q;
    const StepResult res = sim.step(scene.state);
    EXPECT_TRUE(res.ok()) << name << " step " << i << ": " << res.message;
    if (!res.ok()) break;
    r.max_step_travel_cm = std::max(
        r.max_step_travel_cm,
        (scene.state.q - before).reshaped(3, sim.model().num_cp()).colwise().norm().maxCoeff());
    EXPECT_TRUE(data.contact.present);
    r.min_d = std::min(r.min_d, data.contact.min_distance_ratio);
    r.contact_steps += data.contact.point_pairs_in_contact > 0;
  }
  r.max_length_violation = FastProjection::max_length_violation(sim.model(), scene.state.q);
  return r;
}

TEST(ContactScenes, OverhandKnotPulledTightNeverPassesThroughItself) {
  const SceneRun r = run_scene("overhand_knot.json", 0.3);
  EXPECT_GT(r.contact_steps, 100) << "the knot never tightened into contact";
  EXPECT_GT(r.min_d, 0.5) << "strands came within half a contact distance";
  // a strand moving less than a yarn radius per step cannot jump through another
  EXPECT_LT(r.max_step_travel_cm, 0.125);
  EXPECT_LT(r.max_length_violation, 1e-6);
}

TEST(ContactScenes, YarnDroppedOnTautYarnRestsOnIt) {
  const SceneRun r = run_scene("drop_on_yarn.json", 0.5);
  EXPECT_GT(r.contact_steps, 100);
  EXPECT_GT(r.min_d, 0.5);
  EXPECT_LT(r.max_step_travel_cm, 0.125);
}

}  // namespace
}  // namespace knit
