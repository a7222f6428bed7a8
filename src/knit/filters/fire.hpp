#pragma once
// FIRE, the fast inertial relaxation engine (Bitzek, Koskinen, Gähler, Moseler and
// Gumbsch 2006), as a velocity filter: relaxation to rest as a minimisation of the
// potential energy subject to the constraints, which uses the step itself (explicit or
// IMEX, with the projection) as its integrator and replaces the damping that a dynamic
// relaxation relies on.
//
// Damped dynamics reach rest slowly where the fabric is soft: the non-rigid damping
// filter and the global damping drag every slow, sample-wide motion (a swatch drawing
// in, an edge rolling) as hard as the fast ones, so those motions creep. FIRE lets the
// yarn move undamped downhill and steers it instead. After each step, with a the step's
// constrained acceleration (v after the projection − v at its start) / h and P = Σ m a·v
// the power of the net force:
//   P > 0: v ← (1 − α) v + α (|v|_M / |a|_M) a   (turn the motion toward the force; after
//          more than N_MIN such steps in a row α ← α F_ALPHA, letting the yarn coast)
//   P ≤ 0: v ← 0, α ← α_START                   (it went uphill: stop, start again)
// with |x|_M = √(Σ m x²). Mass-weighted norms make the mixing the same in every
// coordinate whatever a control point's lumped mass. The time step stays fixed (the
// step's stability bound is what limits it); FIRE's other half, a growing step, is left
// to the integrator.
//
// It must be the only velocity filter: it reads the step's acceleration from the change
// of velocity since its own last output. It conserves nothing (momentum decays with
// every mixing and restart): a relaxation only, never a simulation.
#include <Eigen/Core>
#include <string_view>

#include "knit/filters/velocity_filter.hpp"

namespace knit {

class FireFilter : public VelocityFilter {
 public:
  static constexpr double ALPHA_START = 0.1;  ///< mixing per step after a restart
  static constexpr double F_ALPHA = 0.99;     ///< α's decay per step while going downhill
  static constexpr int N_MIN = 5;             ///< downhill steps before α decays

  std::string_view name() const override { return "fire"; }
  void apply(const Model& model, const Eigen::VectorXd& q, Eigen::VectorXd& v, double time,
             double h) override;
  /// Back to before the last apply (its output, α, the downhill run and the restart
  /// count), so that the step taken again compares with the velocities it starts from.
  void reject_step() override;

  /// Forgets the last output and starts again at α_START (a new relaxation, e.g. after a
  /// clamp moved); the restart count is kept.
  void reset() {
    m_has_prev = false;
    m_alpha = ALPHA_START;
    m_downhill = 0;
    m_can_reject = false;
  }
  /// Times the yarn was stopped because it went uphill (P ≤ 0).
  long long restarts() const { return m_restarts; }
  double alpha() const { return m_alpha; }

 private:
  Eigen::VectorXd m_prev;  // the velocities of the last output
  bool m_has_prev = false;
  double m_alpha = ALPHA_START;
  int m_downhill = 0;
  long long m_restarts = 0;
  // as they were before the last apply (reject_step)
  struct Saved {
    bool has_prev = false;
    double alpha = ALPHA_START;
    int downhill = 0;
    long long restarts = 0;
  } m_saved;
  Eigen::VectorXd m_saved_prev;
  bool m_can_reject = false;
};

}  // namespace knit
