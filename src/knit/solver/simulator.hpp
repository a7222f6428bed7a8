#pragma once
// The time step of MODEL.md §5.2 as a sequence of named stages over an immutable Model
// and a mutable State, each writing what it found into StepData:
//   0. forward: the forces at (q, v), recorded (energies, per-term forces, contact set)
//   1. unconstrained explicit-midpoint step of (q, v)       — one more force evaluation
//      (with params.solver.integrator = IMEX, the terms that give a stiffness — the length
//      energy — are left out of it and take one linearly implicit Euler step instead:
//      stages "stiffness" and "implicit")
//   2. fast projection onto the constraint groups, v += Δq / h (multipliers, forces)
//   3. velocity filters (non-rigid damping, object collisions)
//   4. forward at the result, which the next step reuses as its stage 0
// A step that fails leaves the State untouched and reports why: non-finite values, a
// control point moving more than a yarn radius in one step (contact could then let yarns
// pass through each other), or a projection that does not converge.
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "knit/constraints/projection.hpp"
#include "knit/energy/term.hpp"
#include "knit/filters/velocity_filter.hpp"
#include "knit/model/model.hpp"
#include "knit/model/state.hpp"
#include "knit/model/step_data.hpp"
#include "knit/solver/stiff_solve.hpp"

namespace knit {

class ClampGroup;

/// How a step (or a run) ended. INTERRUPTED is a run's status only: a signal asked it to
/// stop after a step that went well.
/// How a step or run ended. NOT_CONVERGED: a quasi-static solve (the elastic sheet's
/// stretch test) did not reach equilibrium.
enum class StepStatus { OK, NON_FINITE, PROJECTION_FAILED, INTERRUPTED, NOT_CONVERGED, CROSSED };

struct StepResult {
  StepStatus status = StepStatus::OK;
  std::string message;
  ProjectionResult projection;
  bool ok() const { return status == StepStatus::OK; }
};

/// The word a summary uses for a status: "ok", "unstable", "projection_failed",
/// "interrupted", "not_converged", "crossed" (yarns passed through each other in a step that
/// SolverSettings::refuse_crossings refused).
const char* status_word(StepStatus status);

class Simulator {
 public:
  /// Builds the default terms for the model's parameters (default_terms, solver/terms.hpp):
  /// gravity, bending, length, global damping (when k_global > 0), yarn–yarn contact (when
  /// material.contact) and the object penalty (when an object has `penalty` on).
  explicit Simulator(Model model);
  /// A simulator with exactly the given terms (for tests and special set-ups).
  Simulator(Model model, std::vector<std::unique_ptr<Term>> terms);

  const Model& model() const { return m_model; }
  void add_term(std::unique_ptr<Term> term);
  void add_filter(std::unique_ptr<VelocityFilter> filter);
  const std::vector<std::unique_ptr<Term>>& terms() const { return m_terms; }

  /// Advances `state` by the model's time step (params.solver.time_step).
  StepResult step(State& state) { return step(state, m_model.params.solver.time_step); }
  /// Advances `state` by h seconds: forward (reused when the state is the one the last
  /// step produced) → explicit midpoint → projection → filters → forward at the result.
  /// On failure `state` is unchanged.
  StepResult step(State& state, double h);
  /// Evaluates the forces at `state` and records them in data() (energies, per-term net
  /// forces, contact set, kinetic energy, max |C|). Does nothing when data() already
  /// describes exactly this state (same q, v and time, bitwise), beyond completing what a
  /// lean step left out there (set_lean_records).
  void forward(const State& state);
  /// With `on`, a step's closing forward (the next step's first evaluation) leaves out what
  /// only the records read, where the IMEX step does not need it: the explicit terms, when
  /// none of them reads the velocities (Term::reads_velocity: the step evaluates them at its
  /// midpoint alone) and some term is implicit. Their energies and net forces in data(),
  /// and the potential energy, are then NaN until forward(state) completes them (those terms
  /// alone, evaluated at the state). Steps are the same to the bit either way. For a
  /// caller that reads whole records only now and then (the runner, at its outputs).
  void set_lean_records(bool on) { m_lean = on; }
  bool lean_records() const { return m_lean; }
  /// Scales the distances of contact reuse (SolverSettings::contact_reuse): an exact
  /// contact evaluation's linearisation and the kept matrix M + h² K are reused while every
  /// control point stays within `scale` ρ r of where they were formed. 1 at first; a
  /// relaxation widens it while far from rest (RelaxOptions::contact_reuse_widen). Throws
  /// std::invalid_argument unless finite and > 0. Recorded in data().reuse_scale.
  void set_reuse_scale(double scale);
  double reuse_scale() const { return m_reuse_scale; }
  /// What the last forward and step recorded (see step_data.hpp).
  const StepData& data() const { return m_data; }
  /// Clears the stage timings in data().
  void reset_timings() { m_data.stage_seconds.clear(); }

  /// Stage 1: the generalised force on the control points (dyn) at (q, v) and `time` (s);
  /// returns the total potential energy (erg). Records nothing.
  double compute_forces(const Eigen::VectorXd& q, const Eigen::VectorXd& v, double time,
                        Eigen::VectorXd& force);
  /// Stage 1: the unconstrained explicit-midpoint step from (q, v) into (q_out, v_out).
  void unconstrained_step(const State& state, double h, Eigen::VectorXd& q_out,
                          Eigen::VectorXd& v_out);
  /// Stage 1 of the IMEX integrator: the terms without a stiffness at the explicit
  /// midpoint (q + h/2 v, v + h/2 M⁻¹ f(q, v)), those with one (K, f_I) linearly implicit:
  /// (M + h² K) Δv = h (f_E(mid) + f_I(q)) − h² K v, v⁺ = v + Δv, q⁺ = q + h v⁺ (a state
  /// at rest stays at rest). Glues and pins (few rows, constant ∇C = J) enter the solve
  /// as constraints on the new velocity, J v⁺ = −C(q, t + h) / h, with multipliers μ:
  /// (M + h² K) Δv + Jᵀ μ = b. A clamp's control points are given their new velocity,
  /// the one that takes them to the clamp's target at t + h, and leave the unknowns.
  /// Without them the solve (which sees K but not the constraint) and the projection
  /// after it (which sees the constraint but not K, in the metric M) would come to rest
  /// where they balance, not where the forces do: up to 10⁵ cm/s² of net force left on a
  /// glued yarn end, 5 × 10⁵ on a pinned one. The length constraints (with
  /// params.solver.length_constraints) enter as stiff penalty rows on their linearisation,
  /// ρ_i ∇C_iᵀ ∇C_i in segment i's block (add_length_rows), for the same reason. Returns
  /// false when M + h² K could not be factored.
  bool imex_step(const State& state, double h, Eigen::VectorXd& q_out, Eigen::VectorXd& v_out);
  /// Stage 2: projects q (in place) at `time`, correcting v by the displacement / h.
  ProjectionResult project(Eigen::VectorXd& q, Eigen::VectorXd& v, double time, double h);
  /// Moves the positions onto the constraints (no velocity change): call once before a
  /// run whose initial state may violate them (e.g. glued yarn ends laid a yarn diameter
  /// from the point they are glued to).
  ProjectionResult satisfy_constraints(State& state);
  /// Stage 3: every velocity filter in order, at the end (`time`) of a step of length h
  /// (step() first shows each the step's start: begin_step).
  void apply_filters(const Eigen::VectorXd& q, Eigen::VectorXd& v, double time, double h);

  /// The force residual at `state` (cm/s²): the net static force per unit mass that the
  /// constraints do not hold — f(q) from every term at v = 0, M⁻¹ f with the part along
  /// the constraint normals removed by the projection's mass-weighted metric, its
  /// mass-weighted RMS over control points. 0 exactly at a constrained minimum (or
  /// saddle) of the potential energy, however the yarn got there; compare it with
  /// g = 981 cm/s². Records it in data().force_residual (after a forward at the state),
  /// and the constraint groups' static reactions in data().static_constraints.
  /// Costs a force evaluation and two projections.
  double force_residual(const State& state);
  /// ½ vᵀ M v (erg) with the lumped mass.
  double kinetic_energy(const State& state) const;
  /// Σ of the terms' potential energies (erg), evaluated afresh (for tests and tools;
  /// runs read data().potential_energy).
  double potential_energy(const State& state);
  /// Linear momentum Σ m_k v_k (g cm/s).
  Eigen::Vector3d linear_momentum(const State& state) const;
  /// Angular momentum about the origin Σ m_k q_k × v_k (g cm²/s).
  Eigen::Vector3d angular_momentum(const State& state) const;
  /// max |C| over all constraint groups at the state's time, evaluated afresh.
  double max_violation(const State& state) {
    return m_projection.max_violation(m_model, state.q, state.time);
  }

 private:
  void forward(const State& state, double known_violation, bool lean);
  // whether a lean forward may leave out the explicit terms (set_lean_records)
  bool can_leave_out_explicit() const;
  // evaluates and records the terms a lean forward left out, at `state`
  void complete_records(const State& state);
  Model m_model;
  std::vector<std::unique_ptr<Term>> m_terms;
  std::vector<std::unique_ptr<VelocityFilter>> m_filters;
  FastProjection m_projection;
  StepData m_data;
  // the state data() describes, and the force there (reused as a step's first evaluation)
  bool m_cached = false;
  bool m_lean = false;
  double m_reuse_scale = 1;  // set_reuse_scale
  // the terms (indices) the cached forward left out, and the energy of the others
  std::vector<size_t> m_left_out;
  double m_recorded_energy = 0;
  Eigen::VectorXd m_cache_q, m_cache_v, m_force0;
  double m_cache_time = 0;
  Eigen::VectorXd m_force, m_qmid, m_vmid, m_qnew, m_vnew, m_qpre;
  // the IMEX step's implicit part
  std::vector<Matrix12d> m_blocks, m_term_blocks;
  Eigen::VectorXd m_force_implicit, m_force_term, m_rhs, m_dv;
  Eigen::VectorXd m_mass3;      // m per coordinate
  bool m_seg_ascending = true;  // each segment's first control point after the one before's
  StiffSolver m_stiff;
  // the glues' rows in the IMEX solve: ∇C as sparse rows (dof, value), built once
  // The constraints the IMEX solve holds, built once: the clamps' control points as
  // given velocities (fixed coordinates of the band solve), the glues' and pins' rows as
  // constraints with multipliers.
  void build_solve_constraints();
  // kept: the matrix is the last step's (W and S are kept with it); halfway: dv is the
  // solve's forward half L⁻¹ b, corrected in place before its backward half
  void hold_glues_in_solve(const State& state, double h, Eigen::VectorXd& dv, bool kept,
                           bool halfway);
  bool m_solve_constraints_built = false;
  struct ClampedPoint {
    const ClampGroup* group;
    int index;  // the held point's index in the clamp (points first, then control points)
    int cp;     // the control point
  };
  std::vector<ClampedPoint> m_clamped;
  std::vector<int> m_fixed_dofs;
  std::vector<int> m_fixed_segments;  // those touching a clamped control point
  std::vector<const ConstraintGroup*> m_solve_groups;
  // per row: its free coordinates, all its coordinates, its index among the groups' rows
  std::vector<std::vector<std::pair<int, double>>> m_glue_rows, m_glue_rows_all;
  std::vector<int> m_glue_row_of;
  std::vector<std::pair<int, int>> m_glue_row_group;  // (group, its row) of each row
  Eigen::VectorXd m_glue_mu;                          // the last solve's multipliers
  std::vector<int> m_fixed_group;                     // the clamp of each fixed coordinate
  std::vector<double> m_b_fixed, m_fixed_residual;
  // what the solve's constraints exerted in the last IMEX step, per constraint group
  std::vector<Eigen::Vector3d> m_solve_force, m_solve_torque, m_solve_about;
  void record_solve_forces(const Eigen::VectorXd& q, double time, double h);
  Eigen::VectorXd m_glue_c;
  StiffSolver::RowMajorMatrix m_glue_y;  // L⁻¹ ∇Cᵀ, with M + h² K = L Lᵀ
  // each column's rows where it is not 0: [first, end) (StiffSolver::forward_columns)
  std::vector<int> m_glue_first, m_glue_end;
  template <class F>
  double glue_column_dot(int r, F&& value, int from = 0,
                         int to = std::numeric_limits<int>::max()) const;
  Eigen::LDLT<Eigen::MatrixXd> m_glue_s;  // S = J A⁻¹ Jᵀ
  // the kept matrix (contact reuse, imex_step): whether the factor, m_blocks and the glues'
  // W and S may be reused, whether it has stiffness blocks, its h and where it was formed
  bool m_kept_valid = false, m_kept_any = false;
  double m_kept_h = 0;
  Eigen::VectorXd m_kept_q;
  // IMEX_CONTACT: whether a term is taken implicitly; the operator terms' part of the
  // solve by preconditioned conjugate gradients
  bool implicit(const Term& term) const;
  void enable_operator_stiffness(Term& term);
  void add_operator_product(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
  void band_product(const Eigen::VectorXd& x, double h2, Eigen::VectorXd& y) const;
  // y += h2 Σ blocks x, from m_packed: each block's upper triangle (pack_blocks, after
  // every change of m_blocks)
  void add_blocks_product(const Eigen::VectorXd& x, double h2, Eigen::VectorXd& y) const;
  void pack_blocks();
  static constexpr int PACKED = 78;
  std::vector<double> m_packed;
  void solve_with_operator(const State& state, double h);
  // the length constraints as rows of the IMEX solve: their gradients ∇C_i, values C_i and
  // penalty stiffness ρ_i at the step's start
  void add_length_rows(const State& state, double h);
  static constexpr double LENGTH_ROW_STIFFNESS = 1e8;
  std::vector<Vector12d> m_len_grad;
  std::vector<double> m_len_c, m_len_rho;
  static constexpr int MAX_CG_ITERATIONS = 100;
  bool m_has_operator_terms = false;
  Eigen::VectorXd m_cg_r, m_cg_z, m_cg_p, m_cg_ap, m_cg_kp, m_cg_kx;
};

}  // namespace knit
