// The hold filter: outside its windows the wrapped filters act, inside them FIRE, which
// starts afresh at each window (its first step there only remembers the velocities).
#include "knit/filters/hold_relax.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace knit {
namespace {

// a filter that halves every velocity and counts its calls
class Halve : public VelocityFilter {
 public:
  explicit Halve(int* calls) : m_calls(calls) {}
  std::string_view name() const override { return "halve"; }
  void apply(const Model&, const Eigen::VectorXd&, Eigen::VectorXd& v, double, double) override {
    v *= 0.5;
    ++*m_calls;
  }

 private:
  int* m_calls;
};

Model short_yarn() {
  ModelBuilder b;
  Eigen::Matrix3Xd cp(3, 5);
  for (int k = 0; k < 5; ++k) cp.col(k) = Eigen::Vector3d(0.5 * k, 0, 0);
  b.add_yarn(cp);
  return b.build(Params{});
}

TEST(HoldRelax, WindowsHoldTheStepsThatEndInThem) {
  int calls = 0;
  std::vector<std::unique_ptr<VelocityFilter>> outside;
  outside.push_back(std::make_unique<Halve>(&calls));
  const HoldRelaxFilter f(std::move(outside), {{0.0, 1.0}, {2.0, 3.0}});
  EXPECT_EQ(f.window_at(0.0), -1);  // a window's start is not in it
  EXPECT_EQ(f.window_at(0.5), 0);
  EXPECT_EQ(f.window_at(1.0), 0);  // its end is
  EXPECT_EQ(f.window_at(1.5), -1);
  EXPECT_EQ(f.window_at(2.0 + 1e-12), -1);  // within rounding of the start: outside
  EXPECT_EQ(f.window_at(3.0 - 1e-12), 1);
  EXPECT_EQ(f.window_at(3.5), -1);
}

TEST(HoldRelax, FireInsideTheWrappedFiltersOutsideAndAFreshStartPerWindow) {
  const Model m = short_yarn();
  int calls = 0;
  std::vector<std::unique_ptr<VelocityFilter>> outside;
  outside.push_back(std::make_unique<Halve>(&calls));
  HoldRelaxFilter f(std::move(outside), {{0.0, 1.0}, {2.0, 3.0}});
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(m.num_dof());
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(m.num_dof());
  const double h = 0.25;
  // in the first window: the first step only remembers; an uphill one stops the yarn
  Eigen::VectorXd v = ones;
  f.apply(m, q, v, 0.25, h);
  EXPECT_EQ(v, ones);
  v = 0.5 * ones;  // slowed down: the force opposes the motion
  f.apply(m, q, v, 0.5, h);
  EXPECT_EQ(v.norm(), 0.0);
  EXPECT_EQ(f.fire_restarts(), 1);
  EXPECT_EQ(calls, 0);
  // between the windows: the wrapped filter
  v = ones;
  f.apply(m, q, v, 1.5, h);
  EXPECT_EQ(v, 0.5 * ones);
  EXPECT_EQ(calls, 1);
  // the second window starts afresh: its first step remembers, whatever came before
  v = ones;
  f.apply(m, q, v, 2.25, h);
  EXPECT_EQ(v, ones);
  EXPECT_EQ(f.fire_restarts(), 1);
}

TEST(HoldRelax, WindowsMustBeOrderedAndDisjoint) {
  EXPECT_THROW(HoldRelaxFilter({}, {{1.0, 0.5}}), std::invalid_argument);
  EXPECT_THROW(HoldRelaxFilter({}, {{0.0, 1.0}, {0.5, 2.0}}), std::invalid_argument);
}

}  // namespace
}  // namespace knit
