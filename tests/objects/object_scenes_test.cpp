// Yarn against solid objects, checked by mechanics with analytic answers: a dropped yarn
// comes to rest on a plane and never passes below it; on an incline it sticks when
// tan θ < μ and slides with a = g (sin θ − μ cos θ) when tan θ > μ; a moving plane carries
// a yarn by friction (μ large) or leaves it behind (μ = 0); a moving sphere pushes a yarn
// along its own direction. Scenes are written as scene files, so the parser is covered too.
#include <gtest/gtest.h>

#include <cmath>

#include "knit/objects/object.hpp"
#include "knit/recipes/simulate_scene.hpp"
#include "knit/scene/scene.hpp"

namespace knit {
namespace {

using Eigen::Vector3d;

Scene scene_from(const nlohmann::json& doc) {
  return parse_scene(doc, "objects_test.json");
}

// a straight yarn from a to b
nlohmann::json line(const Vector3d& a, const Vector3d& b, int segments) {
  return {
      {"line",
       {{"from", {a.x(), a.y(), a.z()}}, {"to", {b.x(), b.y(), b.z()}}, {"segments", segments}}}};
}

Vector3d momentum(const Simulator& sim, const State& s) {
  return sim.linear_momentum(s);
}

double total_mass(const Model& m) {
  return m.mass.sum();
}

// the lowest point of the centreline above the plane z = 0, over the energy quadrature
double lowest_height(const Model& m, const Eigen::VectorXd& q) {
  double low = 1e9;
  for (int i = 0; i < m.num_seg(); ++i)
    for (int k = 0; k <= 20; ++k) low = std::min(low, point_position(m, q, {i, k / 20.0}).z());
  return low;
}

TEST(ObjectScenes, DroppedYarnRestsOnThePlaneAndNeverPassesBelowIt) {
  for (const char* mechanism : {"filter", "penalty"}) {
    nlohmann::json doc = {
        {"yarns", {line({-3, 0, 1.0}, {3, 0.5, 1.2}, 12)}},
        {"params", {{"k_global", 0.5}}},
        {"objects",
         {{{"name", "floor"}, {"plane", {{"normal", {0, 0, 1}}}}, {"mechanism", mechanism}}}}};
    if (std::string(mechanism) == "penalty") {
      doc["objects"][0]["stiffness"] = 1e5;
      doc["objects"][0]["damping"] = 10;
    }
    Scene scene = scene_from(doc);
    const double r = scene.model.params.material.radius;
    auto sim = make_scene_simulator(scene);
    State s = scene.state;
    double deepest = 0;
    for (int step = 0; step < 6000; ++step) {  // 0.6 s at h = 1e-4
      ASSERT_TRUE(sim->step(s, 1e-4).ok()) << mechanism << " step " << step;
      deepest = std::max(deepest, sim->data().object("floor")->deepest_penetration);
      if (step % 50 == 0) deepest = std::max(deepest, r - lowest_height(sim->model(), s.q));
    }
    EXPECT_LT(deepest, 0.02) << mechanism << ": the tube went into the plane by " << deepest
                             << " cm";
    const double low = lowest_height(sim->model(), s.q);
    EXPECT_NEAR(low, r, 0.01) << mechanism << ": at rest the tube touches the plane";
    EXPECT_LT(sim->kinetic_energy(s) / sim->model().total_length(), 1e-3) << mechanism;
    // it rests: the object carries the yarn's weight
    const ObjectRecord* floor = sim->data().object("floor");
    ASSERT_NE(floor, nullptr);
    EXPECT_GT(floor->points_in_contact, 0);
    const double weight = total_mass(sim->model()) * 981;
    EXPECT_NEAR(floor->force.z(), weight, 0.1 * weight) << mechanism;
  }
}

// a straight yarn down the slope of a plane tilted by θ, starting at rest on it
struct Incline {
  double theta, mu;
  Vector3d down, normal;
  Scene scene;
};

Incline incline(double theta_deg, double mu) {
  Incline in;
  in.theta = theta_deg * M_PI / 180;
  in.mu = mu;
  in.normal = Vector3d(std::sin(in.theta), 0, std::cos(in.theta));
  in.down = Vector3d(std::cos(in.theta), 0, -std::sin(in.theta));
  const double r = 0.125;
  const Vector3d a = -3 * in.down + r * in.normal, b = 3 * in.down + r * in.normal;
  in.scene = scene_from({{"yarns", {line(a, b, 12)}},
                         {"objects",
                          {{{"name", "slope"},
                            {"plane", {{"normal", {in.normal.x(), in.normal.y(), in.normal.z()}}}},
                            {"friction", mu}}}}});
  return in;
}

TEST(ObjectScenes, YarnOnAnInclineSticksBelowTheFrictionAngle) {
  Incline in = incline(20, 0.5);  // tan 20° = 0.36 < 0.5
  auto sim = make_scene_simulator(in.scene);
  State s = in.scene.state;
  const Vector3d start = point_position(sim->model(), s.q, {6, 0.5});
  for (int step = 0; step < 2000; ++step) ASSERT_TRUE(sim->step(s, 1e-4).ok());
  const Vector3d moved = point_position(sim->model(), s.q, {6, 0.5}) - start;
  // sliding freely it would have gone ½ g sin θ t² = 6.7 cm
  EXPECT_LT(std::abs(moved.dot(in.down)), 1e-5) << "slid " << moved.dot(in.down) << " cm";
}

TEST(ObjectScenes, YarnOnAnInclineSlidesWithTheCoulombAcceleration) {
  for (auto [theta, mu] : {std::pair{30.0, 0.3}, {35.0, 0.0}}) {
    Incline in = incline(theta, mu);
    auto sim = make_scene_simulator(in.scene);
    State s = in.scene.state;
    const double m = total_mass(sim->model());
    auto speed = [&] { return momentum(*sim, s).dot(in.down) / m; };
    for (int step = 0; step < 500; ++step) ASSERT_TRUE(sim->step(s, 1e-4).ok());
    const double t0 = s.time, v0 = speed();
    for (int step = 0; step < 1500; ++step) ASSERT_TRUE(sim->step(s, 1e-4).ok());
    const double a = (speed() - v0) / (s.time - t0);
    const double expected = 981 * (std::sin(in.theta) - mu * std::cos(in.theta));
    EXPECT_NEAR(a, expected, 0.05 * expected) << "θ = " << theta << "°, μ = " << mu;
    // and it stays on the plane
    EXPECT_LT(sim->data().object("slope")->deepest_penetration, 0.01);
  }
}

TEST(ObjectScenes, AMovingPlaneCarriesAYarnByFrictionOrLeavesItBehind) {
  for (double mu : {1.0, 0.0}) {
    Scene scene = scene_from(
        {{"yarns", {line({-2, 0, 0.125}, {2, 0, 0.125}, 8)}},
         {"objects",
          {{{"name", "belt"},
            {"plane", {{"normal", {0, 0, 1}}}},
            {"friction", mu},
            {"keyframes", {{{"time", 0}}, {{"time", 10}, {"translate", {200, 0, 0}}}}}}}}});
    auto sim = make_scene_simulator(scene);
    State s = scene.state;
    for (int step = 0; step < 2000; ++step) ASSERT_TRUE(sim->step(s, 1e-4).ok());
    const double vx = momentum(*sim, s).x() / total_mass(sim->model());
    if (mu > 0)
      EXPECT_NEAR(vx, 20, 0.4) << "μ = 1: carried at the belt's 20 cm/s";
    else
      EXPECT_NEAR(vx, 0, 1e-6) << "μ = 0: left behind";
  }
}

TEST(ObjectScenes, AMovingSpherePushesAYarnAlongItsOwnDirection) {
  for (const char* mechanism : {"penalty", "filter"}) {
    // no gravity: a free yarn across the path of a sphere moving at 30 cm/s along +x
    Scene scene = scene_from(
        {{"yarns", {line({0, -3, 0}, {0, 3, 0}, 12)}},
         {"gravity", {0, 0, 0}},
         {"objects",
          {{{"name", "ball"},
            {"sphere", {{"radius", 1.0}}},
            {"position", {-1.5, 0, 0}},
            {"mechanism", mechanism},
            {"keyframes", {{{"time", 0}}, {{"time", 1}, {"translate", {30, 0, 0}}}}}}}}});
    auto sim = make_scene_simulator(scene);
    State s = scene.state;
    for (int step = 0; step < 1500; ++step) ASSERT_TRUE(sim->step(s, 1e-4).ok()) << mechanism;
    const Vector3d p = momentum(*sim, s);
    const double m = total_mass(sim->model());
    EXPECT_GT(p.x(), 0.5 * m * 30) << mechanism << ": pushed along +x";
    EXPECT_LT(std::abs(p.y()) + std::abs(p.z()), 0.02 * p.x()) << mechanism << ": and only along x";
  }
}

TEST(ObjectScenes, AYarnStartingInsideAnObjectIsRefusedNamingIt) {
  Scene scene = scene_from({{"yarns", {line({-3, 0, 0.5}, {3, 0, 0.5}, 12)}},
                            {"objects", {{{"name", "rock"}, {"sphere", {{"radius", 1.0}}}}}}});
  try {
    simulate_scene(scene, SimulateOptions{});
    FAIL() << "a yarn through a sphere was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("inside object \"rock\""), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace knit
