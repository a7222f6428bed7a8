#pragma once
// Yarn–yarn Coulomb friction as a velocity filter (docs/model.md §5.3; an addition to the
// paper's model, whose contact damping is viscous: a pulled knit's force then depends on
// the pulling speed, and at rest nothing holds its loops where they are).
//
// At every segment pair in contact at the step's start (StepData's contact set: the
// closest point pair, at curve parameters t_i on segment i and t_j on j, and the normal
// force N that i exerts on j), after the constrained step, with the coefficient μ
// (Material::yarn_friction):
//   c_k = B_k(t_j) on j's control points, −B_k(t_i) on i's (summed where they share one),
//   Δ = Σ c_k q_k, the offset of y_j(t_j) from y_i(t_i), and n = Δ/|Δ| at the step's result;
//   u = (Δ(result) − Δ(start)) / h, how fast the points moved against each other over the
//   step (cm/s), and u_t = u − (u·n) n its sliding part;
//   an impulse λ ⊥ n on y_j(t_j) and −λ on y_i(t_i), Δv_k = c_k λ / M_k, with
//   |λ| ≤ μ max(N, 0) h (Coulomb's cone over the step, g cm/s), chosen to stop the
//   sliding: λ = −m u_t with 1/m = Σ c_k² / M_k (the mass the impulse moves), clamped to
//   the cone. A pair sticks when its cone allows that, and slides with its rate changed by
//   the cone's bound otherwise.
// The impulse changes the velocities by Δv and the step's positions by h Δv
// (adjust_positions), so a stuck pair ends the step where it started, relative to its
// partner. Sliding is measured on positions rather than on the velocities because the
// projection leaves a velocity of ½ h a on points that a constraint holds still (a pinned
// or clamped point, a yarn under tension): that velocity never moves them, and friction
// against it would drag their partners along.
// Pairs share control points, so the impulses are found by projected Gauss–Seidel: at most
// PASSES sweeps in a fixed order over the pairs (deterministic, serial), each pair's
// accumulated impulse kept in its cone. Neighbouring pairs of two yarns share most of their
// control points, which makes the sweeps converge slowly; each pair therefore starts from
// its impulse of the last step (warm start: a pair that stays in contact keeps its
// friction, turned into the new tangent plane and cut to the new cone), so a contact that
// sticks for many steps converges over them. Four sweeps per step are enough: on a 12×12
// stockinette pulled along the course (2 cm/s, μ = 0.3) 4 against 16 changed the force by
// at most 0.6 % at every strain and cut the filter's time 2.9× (SOR with ω = 1.5 did not
// converge faster). Each update minimises ½ Σ M_k |q_k(result) −
// q_k(start)|² / h² over that pair's λ within its cone, so the filter only ever slows the step's
// relative motion; its impulses are equal and opposite, so it conserves linear momentum.
#include <vector>

#include "knit/filters/velocity_filter.hpp"

namespace knit {

class YarnFrictionFilter : public VelocityFilter {
 public:
  static constexpr int PASSES = 4;
  /// The sweeps stop when no pair's rate changed by more than this fraction of the
  /// largest rate an impulse has stopped.
  static constexpr double TOLERANCE = 1e-3;
  /// Friction with coefficient `mu` (≥ 0; 0: the filter does nothing).
  explicit YarnFrictionFilter(double mu) : m_mu(mu) {}
  std::string_view name() const override { return "yarn_friction"; }
  /// Keeps the contact set of the step's start (its pairs, parameters, normal forces) and
  /// its positions.
  void begin_step(const StepData& start, const Eigen::VectorXd& q_start) override;
  void apply(const Model& model, const Eigen::VectorXd& q, Eigen::VectorXd& v, double time,
             double h) override;
  bool adjust_positions(const Model& model, Eigen::VectorXd& q) const override;
  /// data.friction: pairs, how many stuck, the energy dissipated, the force.
  /// Back to the warm start before the last apply.
  void reject_step() override;
  void record(StepData& data) const override;
  double mu() const { return m_mu; }

 private:
  double m_mu;
  double m_h = 0;
  std::vector<ContactPairRecord> m_pairs;  // the contact set of the step's start
  Eigen::VectorXd m_q_start;               // and its positions
  // per pair of the last apply: its control points and coefficients, and λ
  struct Row {
    int seg_i = 0, seg_j = 0;
    int n = 0;         // control points (≤ 8)
    int cp[8];         // their indices
    double c[8];       // their coefficients c_k
    double cm[8];      // and c_k / M_k
    double inv_m = 0;  // Σ c_k² / M_k
    double bound = 0;  // μ N h (g cm/s)
    Eigen::Vector3d normal, lambda;
    Eigen::Vector3d rate;  // u: how fast Δ changed over the step (cm/s)
  };
  std::vector<Row> m_rows;
  // the last step's impulses, by segment pair (sorted), for the warm start
  struct Kept {
    int seg_i, seg_j;
    Eigen::Vector3d lambda;
  };
  std::vector<Kept> m_kept, m_kept_before;
  bool m_can_reject = false;
  Eigen::VectorXd m_dv;  // the filter's Δv on the control points
  FrictionRecord m_record;
};

}  // namespace knit
