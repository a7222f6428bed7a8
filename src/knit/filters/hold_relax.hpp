#pragma once
// Holds as relaxations: a velocity filter that, during given windows of time (a stretch
// test's holds, when the clamps stand still), lets FIRE (fire.hpp) steer the yarn to a
// rest of its potential energy, restarted at the start of each window, and outside them
// applies the filters it wraps (non-rigid damping while the clamp moves).
//
// A loading in steps: move, hold until the forces (nearly) balance, sample, move again. The
// damping filters' drag, which makes a continuous pull's force depend on its speed
// (their rate α/h ≈ 8,000 /s), is off while the forces are measured: at rest it would be
// zero anyway, so the equilibrium the hold reaches is the one the potential energy and
// the constraints define. (Whether there is one near the knit is another matter: a knit
// relaxed with the relaxation parameters unravels under FIRE in the simulation ones, as
// README's stretch tests show.)
#include <memory>
#include <vector>

#include "knit/filters/fire.hpp"

namespace knit {

class HoldRelaxFilter : public VelocityFilter {
 public:
  /// `windows`: [start, end] in s, ordered and disjoint; a step belongs to the window its
  /// end time falls in (start excluded, end included, to 1e-9 s).
  HoldRelaxFilter(std::vector<std::unique_ptr<VelocityFilter>> outside,
                  std::vector<std::pair<double, double>> windows);

  std::string_view name() const override { return "hold_relax"; }
  void begin_step(const StepData& start, const Eigen::VectorXd& q_start) override;
  void apply(const Model& model, const Eigen::VectorXd& q, Eigen::VectorXd& v, double time,
             double h) override;
  bool adjust_positions(const Model& model, Eigen::VectorXd& q) const override;
  void reject_step() override;
  void record(StepData& data) const override;

  /// The window the time falls in, or −1.
  int window_at(double time) const;
  long long fire_restarts() const { return m_fire.restarts(); }

 private:
  std::vector<std::unique_ptr<VelocityFilter>> m_outside;
  std::vector<std::pair<double, double>> m_windows;
  FireFilter m_fire;
  int m_window = -1;           // the window of the last apply (−1: outside)
  int m_window_before = -1;    // and of the apply before it (reject_step)
  bool m_outside_last = true;  // whether the last apply ran the wrapped filters
};

}  // namespace knit
