// The object penalty term (MODEL.md §3): its force is the exact negative gradient of its
// energy (finite differences), for static and moving objects of every kind; its damping
// opposes the velocity relative to the object along the normal; a segment far from every
// object costs nothing.
#include <gtest/gtest.h>

#include "fd_check.hpp"
#include "knit/objects/object.hpp"
#include "knit/objects/object_penalty.hpp"

namespace knit {
namespace {

using Eigen::Vector3d;

// a wavy yarn lying across the top of `shape`, dipping into it by up to ~r
Model yarn_over(ShapePtr shape, bool moving, Eigen::VectorXd& q) {
  ModelBuilder b;
  Eigen::Matrix3Xd cp(3, 14);
  for (int k = 0; k < 14; ++k)
    cp.col(k) = Vector3d(-3 + 0.5 * k, 0.1 * std::sin(k), 2.0 - 0.05 + 0.06 * std::cos(1.3 * k));
  b.add_yarn(cp);
  Model m = b.build(Params::simulation());
  auto o = std::make_shared<SceneObject>();
  o->name = "thing";
  o->shape = std::move(shape);
  o->penalty = true;
  o->filter = false;
  o->stiffness = 3e4;
  o->damping = 5;
  if (moving) {
    Keyframe a, c;
    c.time = 1;
    c.translation = Vector3d(0.3, -0.2, 0.1);
    c.rotation = Eigen::AngleAxisd(0.2, Vector3d(0, 1, 1).normalized());
    o->keyframes = {a, c};
  }
  m.objects = {o};
  q = b.positions();
  return m;
}

TEST(ObjectPenalty, ForceIsTheNegativeGradientOfTheEnergy) {
  const std::vector<std::pair<std::string, ShapePtr>> shapes = {
      {"plane", make_plane(Vector3d(0, 0, 2), Vector3d(0, 0.1, 1))},
      {"sphere", make_sphere(Vector3d(0, 0, -3), 5)},
      {"box", make_box(Vector3d(0, 0, 0), Vector3d(10, 10, 4))},
      {"capsule", make_capsule(Vector3d(-5, 0, 0), Vector3d(5, 0, 0), 2)},
      {"cylinder", make_cylinder(Vector3d(0, -5, 0), Vector3d(0, 5, 0), 2)},
      {"ellipsoid", make_ellipsoid(Vector3d(0, 0, 0), Vector3d(6, 3, 2))},
      {"smooth_union",
       make_union({make_sphere(Vector3d(-2, 0, 0), 2), make_sphere(Vector3d(2, 0, 0), 2)}, 1.0)},
  };
  for (const auto& [name, shape] : shapes)
    for (bool moving : {false, true}) {
      Eigen::VectorXd q;
      const Model m = yarn_over(shape, moving, q);
      ObjectPenalty term(m);
      const double time = 0.5;
      const Eigen::VectorXd v = Eigen::VectorXd::Zero(q.size());
      Eigen::VectorXd f = Eigen::VectorXd::Zero(q.size());
      const double e = term.add_force(m, q, v, time, f);
      ASSERT_GT(e, 0) << name
                      << ": the yarn must dip into the object for the check to mean anything";
      // with zero yarn velocity a moving object's damping adds a force: compare without it
      SceneObject still = *m.objects[0];
      still.damping = 0;
      Model m0 = m;
      m0.objects = {std::make_shared<SceneObject>(still)};
      ObjectPenalty elastic(m0);
      f.setZero();
      elastic.add_force(m0, q, v, time, f);
      test::expect_gradient_matches(
          [&](const Eigen::VectorXd& y) { return elastic.energy(m0, y, time); }, q, -f, 1e-7, 1e-5,
          name + (moving ? " (moving)" : ""));
    }
}

TEST(ObjectPenalty, DampingOpposesTheRelativeNormalVelocity) {
  Eigen::VectorXd q;
  const Model m = yarn_over(make_plane(Vector3d(0, 0, 2), Vector3d(0, 0, 1)), false, q);
  ObjectPenalty term(m);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(q.size()), f0 = v, f1 = v;
  term.add_force(m, q, v, 0, f0);
  for (int k = 0; k < m.num_cp(); ++k) v.segment<3>(3 * k) = Vector3d(3, 1, -2);  // into the plane
  term.add_force(m, q, v, 0, f1);
  Vector3d extra = Vector3d::Zero();
  for (int k = 0; k < m.num_cp(); ++k) extra += (f1 - f0).segment<3>(3 * k);
  EXPECT_GT(extra.z(), 0) << "pushes back against the approach";
  EXPECT_NEAR(extra.x(), 0, 1e-9) << "the normal damping has no tangential part";
}

TEST(ObjectPenalty, FarSegmentsAreSkippedAndFeelNothing) {
  Eigen::VectorXd q;
  Model m = yarn_over(make_sphere(Vector3d(0, 0, -100), 5), false, q);
  ObjectPenalty term(m);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(q.size());
  EXPECT_EQ(term.add_force(m, q, f, 0, f), 0.0);
  EXPECT_EQ(f.norm(), 0.0);
}

}  // namespace
}  // namespace knit
