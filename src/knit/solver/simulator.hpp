#pragma once
// The time step of MODEL.md §5.2 as a sequence of named stages over an immutable Model
// and a mutable State:
//   1. unconstrained explicit-midpoint step of (q, v)       — two force evaluations
//   2. fast projection onto the constraints, v += Δq / h
//   3. velocity filters (non-rigid damping, object collisions)
// A step that fails leaves the State untouched and reports why: non-finite values, a
// control point moving more than a yarn radius in one step (contact could then let yarns
// pass through each other), or a projection that does not converge.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "knit/constraints/projection.hpp"
#include "knit/energy/term.hpp"
#include "knit/filters/velocity_filter.hpp"
#include "knit/model/model.hpp"
#include "knit/model/state.hpp"

namespace knit {

enum class StepStatus { OK, NON_FINITE, PROJECTION_FAILED };

struct StepResult {
  StepStatus status = StepStatus::OK;
  std::string message;
  ProjectionResult projection;
  bool ok() const { return status == StepStatus::OK; }
};

/// The word a summary uses for a status: "ok", "unstable", "projection_failed".
const char* status_word(StepStatus status);

class Simulator {
 public:
  /// Builds the default terms for the model's parameters: gravity, bending, length,
  /// global damping (when k_global > 0) and yarn–yarn contact (when params.contact).
  explicit Simulator(Model model);
  /// A simulator with exactly the given terms (for tests and special set-ups).
  Simulator(Model model, std::vector<std::unique_ptr<Term>> terms);

  const Model& model() const { return m_model; }
  void add_term(std::unique_ptr<Term> term) { m_terms.push_back(std::move(term)); }
  void add_filter(std::unique_ptr<VelocityFilter> filter) {
    m_filters.push_back(std::move(filter));
  }
  /// The term with this name, or nullptr.
  Term* find_term(std::string_view name) const;
  const std::vector<std::unique_ptr<Term>>& terms() const { return m_terms; }

  /// Advances `state` by h seconds. On failure `state` is unchanged.
  StepResult step(State& state, double h);

  /// Stage 1: the generalised force on the control points (dyn) at (q, v); returns the
  /// total potential energy (erg).
  double compute_forces(const Eigen::VectorXd& q, const Eigen::VectorXd& v, Eigen::VectorXd& force);
  /// Stage 1: the unconstrained explicit-midpoint step from (q, v) into (q_out, v_out).
  void unconstrained_step(const State& state, double h, Eigen::VectorXd& q_out,
                          Eigen::VectorXd& v_out);
  /// Stage 2: projects q (in place) at `time`, correcting v by the displacement / h.
  ProjectionResult project(Eigen::VectorXd& q, Eigen::VectorXd& v, double time, double h);
  /// Moves the positions onto the constraints (no velocity change): call once before a
  /// run whose initial state may violate them (e.g. glued yarn ends laid a yarn diameter
  /// from the point they are glued to).
  ProjectionResult satisfy_constraints(State& state);
  /// Stage 3: every velocity filter in order.
  void apply_filters(const Eigen::VectorXd& q, Eigen::VectorXd& v, double time);

  /// ½ vᵀ M v (erg) with the lumped mass.
  double kinetic_energy(const State& state) const;
  /// Σ of the terms' potential energies (erg).
  double potential_energy(const State& state);
  /// Linear momentum Σ m_k v_k (g cm/s).
  Eigen::Vector3d linear_momentum(const State& state) const;
  /// Angular momentum about the origin Σ m_k q_k × v_k (g cm²/s).
  Eigen::Vector3d angular_momentum(const State& state) const;
  /// max |C| over all constraints at the state's time.
  double max_violation(const State& state) {
    return m_projection.max_violation(m_model, state.q, state.time);
  }

  /// Wall-clock seconds spent in each stage so far (term names, "projection", filter names).
  const std::map<std::string, double>& stage_seconds() const { return m_seconds; }
  void reset_timings() { m_seconds.clear(); }

 private:
  Model m_model;
  std::vector<std::unique_ptr<Term>> m_terms;
  std::vector<std::unique_ptr<VelocityFilter>> m_filters;
  FastProjection m_projection;
  std::map<std::string, double> m_seconds;
  Eigen::VectorXd m_force, m_qmid, m_vmid, m_qnew, m_vnew, m_qpre;
};

/// The default terms for a model's parameters (see Simulator(Model)).
std::vector<std::unique_ptr<Term>> default_terms(const Model& model);

}  // namespace knit
