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

// A swatch of `pattern` (6×6 unless told) set up for relaxation in zero gravity with the
// non-rigid damping filters, its glues closing over `close_time`.
struct Swatch {
  Swatch(const char* pattern, double k_global, double close_time, int rows = 6, int cols = 6,
         bool in_the_round = false) {
    KnitOptions ko;
    ko.rows = rows;
    ko.cols = cols;
    ko.in_the_round = in_the_round;
    const GeneratedKnit knit = generate_knit(load_pattern(pattern), ko);
    Params p = Params::relaxation();
    p.gravity.setZero();
    p.k_global = k_global;
    sim = std::make_unique<Simulator>(build_knit_model(knit, p, RELAX_SHRINK, close_time));
    sim->add_filter(std::make_unique<NonRigidDampingFilter>(sim->model(), p.alpha_small,
                                                            p.alpha_large, in_the_round));
    s.q = Eigen::Map<const Eigen::VectorXd>(knit.control_points.data(), knit.control_points.size());
    s.v = Eigen::VectorXd::Zero(s.q.size());
    before = measure_fabric(sim->model(), s.q);
  }
  std::unique_ptr<Simulator> sim;
  State s;
  FabricShape before;
};

TEST(Relaxation, SmallStockinetteSettlesWithoutPassingThrough) {
  const double close_time = 0.02;
  Swatch sw("stockinette", Params::relaxation().k_global, close_time);
  Simulator& sim = *sw.sim;
  const Model& model = sim.model();
  State& s = sw.s;
  const FabricShape& before = sw.before;
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

// Without global damping (the `relax` default) only the non-rigid damping filters, contact
// damping and the projection act on the motion, and each of them only removes energy: once
// the glues have closed (their moving targets do work), kinetic + potential energy never
// rises by more than the integrator's error, while the fabric still draws in.
TEST(Relaxation, WithoutGlobalDampingEnergyOnlyFalls) {
  const double close_time = 0.01;
  Swatch sw("rib2x2", 0.0, close_time);
  Simulator& sim = *sw.sim;
  State& s = sw.s;
  ASSERT_EQ(sim.find_term("global_damping"), nullptr);
  ASSERT_TRUE(sim.satisfy_constraints(s).converged);
  const double h = 1.0 / 11800;
  auto run = [&](int steps) {
    for (int i = 0; i < steps; ++i) {
      const StepResult r = sim.step(s, h);
      ASSERT_TRUE(r.ok()) << "step at t = " << s.time << ": " << r.message;
    }
  };
  run(static_cast<int>(close_time / h) + 10);
  double last = sim.kinetic_energy(s) + sim.potential_energy(s);
  const double scale = last;
  for (int k = 0; k < 12; ++k) {  // to ≈ 0.06 s
    run(50);
    const double e = sim.kinetic_energy(s) + sim.potential_energy(s);
    EXPECT_LE(e, last + 1e-4 * scale) << "energy rose at t = " << s.time;
    last = e;
  }
  const FabricShape after = measure_fabric(sim.model(), s.q);
  EXPECT_LT(after.course_extent_cm, sw.before.course_extent_cm);
  EXPECT_LT(after.wale_extent_cm, sw.before.wale_extent_cm);
}

// A small tube relaxes as `knitsim relax --round` runs it (glues closing over 0.05 s): no
// control point jumps by a yarn radius in a step (the solver's instability check), from
// the first step on, and no yarn passes through another. Garter adds a change between knit
// and purl at the seam of every round.
TEST(Relaxation, SmallTubeRelaxesStably) {
  for (const char* name : {"stockinette", "garter"}) {
    SCOPED_TRACE(name);
    Swatch sw(name, RELAX_K_GLOBAL, 0.05, 4, 8, true);
    Simulator& sim = *sw.sim;
    State& s = sw.s;
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
