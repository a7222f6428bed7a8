// Yarn–yarn Coulomb friction (filters/yarn_friction.hpp), checked by mechanics: a yarn
// lying in the groove between two pinned yarn rails on an incline sticks when friction
// can hold it and otherwise slides with the Coulomb acceleration that the groove's
// geometry predicts; the filter conserves linear momentum and never adds kinetic energy.
#include <gtest/gtest.h>

#include <cmath>

#include "knit/filters/yarn_friction.hpp"
#include "knit/recipes/simulate_scene.hpp"
#include "knit/scene/scene.hpp"

namespace knit {
namespace {

using Eigen::Vector3d;

nlohmann::json line(const Vector3d& a, const Vector3d& b, int segments) {
  return {
      {"line",
       {{"from", {a.x(), a.y(), a.z()}}, {"to", {b.x(), b.y(), b.z()}}, {"segments", segments}}}};
}

// Two rails (yarns 0 and 1) pinned at every segment end, down a slope tilted by θ, their
// centrelines 2s apart across it; a slider (yarn 2) on them in the groove, at rest, its
// centreline 2r from each rail's (just touching).
struct Groove {
  double theta, mu, s;
  Vector3d down, normal, across{0, 1, 0};
  Scene scene;
};

constexpr double R = 0.125;  // the default yarn radius (cm)

Groove groove(double theta_deg, double mu) {
  Groove g;
  g.theta = theta_deg * M_PI / 180;
  g.mu = mu;
  g.s = 1.05 * R;
  g.normal = Vector3d(std::sin(g.theta), 0, std::cos(g.theta));
  g.down = Vector3d(std::cos(g.theta), 0, -std::sin(g.theta));
  const int rail_segments = 24;
  nlohmann::json yarns = nlohmann::json::array(), pins = nlohmann::json::array();
  for (int k = 0; k < 2; ++k) {
    const Vector3d side = (k == 0 ? -g.s : g.s) * g.across;
    yarns.push_back(line(-6 * g.down + side, 6 * g.down + side, rail_segments));
    for (int i = 0; i < rail_segments; ++i) pins.push_back({{"yarn", k}, {"segment", i}, {"t", 0}});
    pins.push_back({{"yarn", k}, {"at", "end"}});
  }
  const double height = std::sqrt(4 * R * R - g.s * g.s);  // touching both rails
  yarns.push_back(line(-3 * g.down + height * g.normal, 3 * g.down + height * g.normal, 12));
  g.scene = parse_scene({{"yarns", yarns},
                         {"pins", pins},
                         {"params", {{"yarn_friction", mu}, {"k_dt", 0}}},
                         {"time_step", 1e-4}},
                        "groove_test.json");
  return g;
}

// the slider's centreline height above the rails' plane and its velocity down the slope
// (mass-weighted over its control points)
struct Slider {
  double height = 0, speed = 0, position = 0;
};

Slider slider(const Model& m, const State& s, const Groove& g) {
  Slider out;
  double mass = 0;
  const auto& y = m.yarns[2];
  for (int k = y.cp_begin + 1; k < y.cp_end - 1; ++k) {  // the inner points lie on the line
    mass += m.mass[k];
    out.height += m.mass[k] * s.q.segment<3>(3 * k).dot(g.normal);
    out.speed += m.mass[k] * s.v.segment<3>(3 * k).dot(g.down);
    out.position += m.mass[k] * s.q.segment<3>(3 * k).dot(g.down);
  }
  out.height /= mass;
  out.speed /= mass;
  out.position /= mass;
  return out;
}

TEST(YarnFriction, AYarnInAGrooveOfYarnsSticksWhenFrictionCanHoldIt) {
  // the groove presses with Σ N = m g cos θ / cos φ (φ: the contact normals' angle from
  // the slope's normal, about 30°); friction holds when μ Σ N ≥ m g sin θ, i.e.
  // tan θ ≤ μ / cos φ: 0.36 against 0.58 here
  Groove g = groove(20, 0.5);
  auto sim = make_scene_simulator(g.scene);
  State s = g.scene.state;
  const double start = slider(sim->model(), s, g).position;
  double settled = 0;
  for (int step = 0; step < 2000; ++step) {
    ASSERT_TRUE(sim->step(s).ok());
    if (step == 499) settled = slider(sim->model(), s, g).position;
  }
  const Slider end = slider(sim->model(), s, g);
  // without friction it would slide ½ g sin θ t² = 6.7 cm in these 0.2 s
  EXPECT_LT(std::abs(end.position - start), 2e-3) << "slid " << end.position - start << " cm";
  // and once settled into the groove it does not creep at all (a velocity of ½ h g sin θ
  // remains, as on any point a constraint holds: the projection's, which never moves it)
  EXPECT_LT(std::abs(end.position - settled), 1e-5) << "crept " << end.position - settled;
  const FrictionRecord& f = sim->data().friction;
  EXPECT_TRUE(f.present);
  EXPECT_GT(f.pairs, 0);
  EXPECT_GT(f.stuck, f.pairs / 2) << "most contacts stick (a few at the yarn's ends, "
                                     "pressed less, may sit at the edge of their cones)";
}

TEST(YarnFriction, AYarnInAGrooveOfYarnsSlidesWithTheCoulombAcceleration) {
  for (auto [theta, mu] : {std::pair{30.0, 0.2}, {30.0, 0.0}}) {
    Groove g = groove(theta, mu);
    auto sim = make_scene_simulator(g.scene);
    State s = g.scene.state;
    for (int step = 0; step < 300; ++step) ASSERT_TRUE(sim->step(s).ok());  // settles in
    const Slider a0 = slider(sim->model(), s, g);
    const double t0 = s.time;
    double height = 0;
    const int steps = 1000;
    for (int step = 0; step < steps; ++step) {
      ASSERT_TRUE(sim->step(s).ok());
      height += slider(sim->model(), s, g).height / steps;
    }
    const Slider a1 = slider(sim->model(), s, g);
    const double a = (a1.speed - a0.speed) / (s.time - t0);
    // the normals point from each rail's centre to the slider's: cos φ = height / √(s² +
    // height²), and the groove's normal forces sum to m g cos θ / cos φ
    const double cos_phi = height / std::hypot(g.s, height);
    const double expected = 981 * (std::sin(g.theta) - mu * std::cos(g.theta) / cos_phi);
    EXPECT_NEAR(a, expected, 0.03 * 981 * std::sin(g.theta))
        << "θ = " << theta << "°, μ = " << mu << ", cos φ = " << cos_phi;
    if (mu > 0) {
      const FrictionRecord& f = sim->data().friction;
      EXPECT_GT(f.pairs, 0);
      EXPECT_EQ(f.stuck, 0) << "every contact slides";
      EXPECT_GT(f.work, 0);
    }
  }
}

TEST(YarnFriction, ConservesMomentumAndOnlyEverSlowsTheStepsRelativeMotion) {
  Groove g = groove(30, 0.3);
  auto sim = make_scene_simulator(g.scene);
  State s = g.scene.state;
  // sliding in the groove; the light yarn rests on the very edge of contact (d ≈ 0.999)
  // and leaves it for a step now and then: go on to a step with contact
  for (int step = 0; step < 200 || sim->data().contact.pairs.empty(); ++step)
    ASSERT_TRUE(step < 400 && sim->step(s).ok());
  const Model& m = sim->model();
  ASSERT_FALSE(sim->data().contact.pairs.empty());
  const double h = 1e-4;
  // an arbitrary step: every control point moved by h u over it, with velocities v; then
  // the filter alone, with a cone that binds for some pairs and not for others
  for (double mu : {0.05, 0.3, 1e3}) {
    Eigen::VectorXd u(s.q.size()), v(s.q.size());
    for (Eigen::Index k = 0; k < u.size(); ++k) {
      u[k] = 0.02 * std::sin(1.7 * k + mu);
      v[k] = 0.01 * std::cos(0.9 * k - mu);
    }
    const Eigen::VectorXd q_start = s.q - h * u, v_before = v;
    Eigen::VectorXd q;
    YarnFrictionFilter filter(mu);
    // the same step again and again: each time the filter starts from its last impulses
    // (a wide cone's sweeps converge slowly; a contact that sticks converges over steps)
    for (int repeat = 0; repeat < (mu == 1e3 ? 10 : 1); ++repeat) {
      q = s.q;
      v = v_before;
      filter.begin_step(sim->data(), q_start);
      filter.apply(m, q, v, s.time, h);
      ASSERT_TRUE(filter.adjust_positions(m, q));
    }
    StepData data;
    filter.record(data);
    // the positions moved by h Δv for the velocities' change Δv
    EXPECT_LT((q - s.q - h * (v - v_before)).cwiseAbs().maxCoeff(), 1e-15);
    Vector3d p0 = Vector3d::Zero(), p1 = Vector3d::Zero();
    double e0 = 0, e1 = 0;  // ½ Σ M |displacement / h|²
    for (int k = 0; k < m.num_cp(); ++k) {
      p0 += m.mass[k] * v_before.segment<3>(3 * k);
      p1 += m.mass[k] * v.segment<3>(3 * k);
      e0 += 0.5 * m.mass[k] * u.segment<3>(3 * k).squaredNorm();
      e1 += 0.5 * m.mass[k] * ((q - q_start) / h).segment<3>(3 * k).squaredNorm();
    }
    EXPECT_LT((p1 - p0).norm(), 1e-12 * m.mass.sum() * 0.02) << "μ = " << mu;
    EXPECT_LT(e1, e0) << "μ = " << mu << ": sliding contacts slow down";
    EXPECT_GT(data.friction.work, 0);
    EXPECT_GT(data.friction.pairs, 0);
    if (mu == 1e3) {
      EXPECT_EQ(data.friction.stuck, data.friction.pairs) << "a wide cone holds";
      // and every pair's points end the step where they started, relative to each other,
      // but for their motion along the normal
      double worst = 0;  // the largest fraction of a pair's sliding left
      for (const ContactPairRecord& p : sim->data().contact.pairs) {
        auto offset = [&](const Eigen::VectorXd& x) {
          return Vector3d(point_position(m, x, {p.seg_j, p.t_j}) -
                          point_position(m, x, {p.seg_i, p.t_i}));
        };
        const Vector3d n = offset(q).normalized(), before = offset(s.q) - offset(q_start),
                       after = offset(q) - offset(q_start);
        worst = std::max(worst,
                         (after - after.dot(n) * n).norm() / (before - before.dot(n) * n).norm());
      }
      // (the sweeps converge slowly on pairs that share most of their control points: a
      // few per cent of the sliding is left after these 10 steps' sweeps)
      EXPECT_LT(worst, 0.05) << "a stuck pair's sliding is stopped";
    }
    if (mu == 0.05) {
      EXPECT_EQ(data.friction.stuck, 0) << "a narrow one lets every pair slide";
    }
  }
}

}  // namespace
}  // namespace knit
