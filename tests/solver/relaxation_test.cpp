// Relaxation of a small generated swatch (MODEL.md §6): it stays interlocked without yarn
// passing through yarn, the glued ends close onto the fabric, the shrunk rest lengths pull
// the fabric in, and the motion dies down.
#include <gtest/gtest.h>

#include "knit/analysis/fabric_shape.hpp"
#include "knit/recipes/relax_knit.hpp"

namespace knit {
namespace {

// A swatch of `pattern` (6×6 unless told) set up for relaxation as relax_knit does it
// (zero gravity, shrunk rest lengths, the non-rigid damping filters), with the given global
// damping, its glues closing over `close_time`.
struct Swatch {
  Swatch(const char* pattern, double k_global, double close_time, int rows = 6, int cols = 6,
         bool in_the_round = false) {
    RelaxKnitOptions o;
    o.knit.rows = rows;
    o.knit.cols = cols;
    o.knit.in_the_round = in_the_round;
    o.params.material.k_global = k_global;
    o.glue_close_time = close_time;
    KnitRelaxation setup = setup_knit_relaxation(pattern, o);
    sim = std::move(setup.sim);
    s = setup.state;
    before = measure_fabric(sim->model(), s.q);
  }
  std::unique_ptr<Simulator> sim;
  State s;
  FabricShape before;
};

TEST(Relaxation, SmallStockinetteSettlesWithoutPassingThrough) {
  const double close_time = 0.02;
  Swatch sw("stockinette", Params::relaxation().material.k_global, close_time);
  Simulator& sim = *sw.sim;
  const Model& model = sim.model();
  State& s = sw.s;
  const FabricShape& before = sw.before;
  ASSERT_TRUE(sim.satisfy_constraints(s).converged);

  const StepData& data = sim.data();
  const double h = 1.0 / 11800;
  double min_d = 1e300, peak_ke = 0;
  for (int i = 0; i < 700; ++i) {  // 0.06 s
    const StepResult r = sim.step(s, h);
    ASSERT_TRUE(r.ok()) << "step " << i << ": " << r.message;
    ASSERT_TRUE(data.contact.present);
    min_d = std::min(min_d, data.contact.min_distance_ratio);
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
  for (const auto& term : sim.terms()) ASSERT_NE(term->name(), "global_damping");
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
    const StepData& data = sim.data();
    double min_d = 1e300;
    for (int i = 0; i < 400; ++i) {  // 0.034 s
      const StepResult r = sim.step(s, 1.0 / 11800);
      ASSERT_TRUE(r.ok()) << "step " << i << ": " << r.message;
      ASSERT_TRUE(data.contact.present);
      min_d = std::min(min_d, data.contact.min_distance_ratio);
    }
    EXPECT_GT(min_d, 0.5) << "yarns came within half a contact distance";
    EXPECT_TRUE(s.q.allFinite());
  }
}

}  // namespace
}  // namespace knit
