// Relaxation of a small generated swatch (MODEL.md §6): it stays interlocked without yarn
// passing through yarn, the glued ends close onto the fabric, the shrunk rest lengths pull
// the fabric in, and the motion dies down.
#include <gtest/gtest.h>

#include "knit/analysis/fabric_shape.hpp"
#include "knit/contact/contact_term.hpp"
#include "knit/filters/nonrigid_damping.hpp"
#include "knit/pattern/generator.hpp"
#include "knit/pattern/pattern.hpp"
#include "knit/solver/relaxation.hpp"

namespace knit {
namespace {

TEST(Relaxation, SmallStockinetteSettlesWithoutPassingThrough) {
  KnitOptions ko;
  ko.rows = 6;
  ko.cols = 6;
  const GeneratedKnit knit = generate_knit(load_pattern("stockinette"), ko);
  Params p = Params::relaxation();
  p.gravity.setZero();
  const double close_time = 0.02;
  const Model model = build_knit_model(knit, p, RELAX_SHRINK, close_time);
  Simulator sim(model);
  sim.add_filter(std::make_unique<NonRigidDampingFilter>(model, p.alpha_small, p.alpha_large));
  State s;
  s.q = Eigen::Map<const Eigen::VectorXd>(knit.control_points.data(), knit.control_points.size());
  s.v = Eigen::VectorXd::Zero(s.q.size());
  const FabricShape before = measure_fabric(model, s.q);
  ASSERT_TRUE(sim.satisfy_constraints(s).converged);

  const auto* contact = dynamic_cast<const ContactTerm*>(sim.find_term("contact"));
  ASSERT_NE(contact, nullptr);
  const double h = 1.0 / 11800;
  double min_d = 1e300, peak_ke = 0;
  for (int i = 0; i < 700; ++i) {  // 0.06 s
    const StepResult r = sim.step(s, h);
    ASSERT_TRUE(r.ok()) << "step " << i << ": " << r.message;
    min_d = std::min(min_d, contact->last_stats().min_distance_ratio);
    peak_ke = std::max(peak_ke, sim.kinetic_energy(s));
  }
  const FabricShape after = measure_fabric(model, s.q);
  EXPECT_GT(min_d, 0.5) << "yarns came within half a contact distance";
  // the glues have closed (their gap ramp ended at close_time)
  for (const Glue& g : model.glues)
    EXPECT_LT((point_position(model, s.q, g.a) - point_position(model, s.q, g.b)).norm(), 1e-5);
  // shrinking every rest length by 6.5 % draws the fabric in
  EXPECT_LT(after.course_extent_cm, before.course_extent_cm);
  EXPECT_LT(after.wale_extent_cm, before.wale_extent_cm);
  // heavy damping: the motion set off by the shrink dies down
  EXPECT_LT(sim.kinetic_energy(s), 0.2 * peak_ke);
}

// A small tube relaxes as `knitsim relax --round` runs it (glues closing over 0.05 s): no
// control point jumps by a yarn radius in a step (the solver's instability check), from
// the first step on, and no yarn passes through another. Garter adds a change between knit
// and purl at the seam of every round.
TEST(Relaxation, SmallTubeRelaxesStably) {
  for (const char* name : {"stockinette", "garter"}) {
    SCOPED_TRACE(name);
    KnitOptions ko;
    ko.rows = 4;
    ko.cols = 8;
    ko.in_the_round = true;
    const GeneratedKnit knit = generate_knit(load_pattern(name), ko);
    Params p = Params::relaxation();
    p.gravity.setZero();
    const Model model = build_knit_model(knit, p, RELAX_SHRINK, 0.05);
    Simulator sim(model);
    sim.add_filter(std::make_unique<NonRigidDampingFilter>(model, p.alpha_small, p.alpha_large));
    State s;
    s.q = Eigen::Map<const Eigen::VectorXd>(knit.control_points.data(), knit.control_points.size());
    s.v = Eigen::VectorXd::Zero(s.q.size());
    const auto* contact = dynamic_cast<const ContactTerm*>(sim.find_term("contact"));
    ASSERT_NE(contact, nullptr);
    double min_d = 1e300;
    for (int i = 0; i < 400; ++i) {  // 0.034 s
      const StepResult r = sim.step(s, 1.0 / 11800);
      ASSERT_TRUE(r.ok()) << "step " << i << ": " << r.message;
      min_d = std::min(min_d, contact->last_stats().min_distance_ratio);
    }
    EXPECT_GT(min_d, 0.5) << "yarns came within half a contact distance";
    EXPECT_TRUE(s.q.allFinite());
  }
}

}  // namespace
}  // namespace knit
