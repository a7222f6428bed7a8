#pragma once
// A physical term of the equations of motion M q̈ = −∇E − ∇_q̇ D + f_ext (MODEL.md §2).
#include <Eigen/Core>
#include <string_view>
#include <vector>

#include "knit/model/model.hpp"
#include "knit/model/step_data.hpp"
#include "knit/spline/basis.hpp"

namespace knit {

class Term {
 public:
  virtual ~Term() = default;
  /// Short stable name ("bending", "contact", …) used in timings and logs.
  virtual std::string_view name() const = 0;
  /// Adds the term's generalised force −∂E/∂q − ∂D/∂q̇ (dyn, per coordinate) at positions q,
  /// velocities v and `time` (s; terms with moving objects depend on it) into `force` and
  /// returns its potential energy E (erg = g cm²/s²; 0 for pure damping).
  virtual double add_force(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                           double time, Eigen::VectorXd& force) = 0;
  /// Writes what the term's last add_force found, beyond its energy and force, into the
  /// step data (the contact term: the contact set and its counters). Called by the
  /// simulator right after the evaluation at a recorded state.
  virtual void record(StepData& data) const {}
  /// The next add_force is evaluated afresh: a term that reuses an earlier evaluation's
  /// model of its force (ContactTerm with SolverSettings::contact_reuse) does not reuse
  /// it. The simulator calls it where a force must be exact (the force residual).
  virtual void refresh() {}
  /// Scales the distance within which the term reuses an earlier evaluation's model of its
  /// force (ContactTerm: SolverSettings::contact_reuse ρ r becomes `scale` ρ r). The
  /// simulator passes on Simulator::set_reuse_scale; a term that reuses nothing ignores it.
  virtual void set_reuse_scale(double scale) {}
  /// Number of add_force calls so far (counted by the terms that are costly to evaluate;
  /// -1 when not counted).
  virtual long long evaluations() const { return -1; }
  /// True for a term the IMEX integrator takes implicitly: it gives segment_stiffness.
  /// Its force must depend on q alone (not on v or time).
  virtual bool has_stiffness() const { return false; }
  /// False for a term whose force does not read the velocities v and that records nothing
  /// beyond its energy (bending, gravity, length): the IMEX step needs such an explicit
  /// term at its midpoint alone, not at its start (Simulator::set_lean_records).
  virtual bool reads_velocity() const { return true; }
  /// Where has_stiffness: its stiffness K ≈ ∂²E/∂q² at q as one positive-semidefinite
  /// 12×12 block per segment (over the segment's four control points; blocks[i] for
  /// segment i; resized here).
  virtual void segment_stiffness(const Model& model, const Eigen::VectorXd& q,
                                 std::vector<Matrix12d>& blocks) {}
  /// True for a term whose stiffness couples segments far apart (yarn–yarn contact): the
  /// IMEX_CONTACT integrator takes it implicitly by applying its stiffness rather than
  /// assembling it. set_operator_stiffness(true) makes every later add_force keep what
  /// add_stiffness_product needs; the force must then depend on the state at the step's
  /// start alone.
  virtual bool has_operator_stiffness() const { return false; }
  virtual void set_operator_stiffness(bool on) {}
  /// Where has_operator_stiffness and it is on: y += K x, with K ≈ ∂²E/∂q² (positive
  /// semidefinite) at the q of the last add_force. x and y: 3 × control points.
  virtual void add_stiffness_product(const Model& model, const Eigen::VectorXd& x,
                                     Eigen::VectorXd& y) const {}
  /// The same product's rows at the control points of `segments` alone (ascending, no
  /// repeats): exact at a control point all of whose segments are listed, partial at the
  /// others (the clamps' reaction needs a few rows, not the whole product).
  virtual void add_stiffness_product_rows(const Model& model, const Eigen::VectorXd& x,
                                          const std::vector<int>& segments,
                                          Eigen::VectorXd& y) const {}
  /// Where add_stiffness_product applies: adds into blocks[i] the part of that stiffness
  /// on segment i's own four control points (the preconditioner of the solve).
  virtual void add_operator_segment_stiffness(const Model& model,
                                              std::vector<Matrix12d>& blocks) const {}
  /// The same for one segment: adds its block into `block`; false (and nothing added)
  /// where that part is zero. Safe to call for different segments at once.
  virtual bool add_operator_segment_block(const Model& model, int segment, Matrix12d& block) const {
    return false;
  }
  /// Potential energy alone (erg) at `time`.
  virtual double energy(const Model& model, const Eigen::VectorXd& q, double time) {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(q.size());
    return add_force(model, q, Eigen::VectorXd::Zero(q.size()), time, f);
  }
};

}  // namespace knit
