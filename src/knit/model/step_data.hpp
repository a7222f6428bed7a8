#pragma once
// StepData: what the stages of a step computed, for everything that reads results — the
// log, the summary, the progress line, the benchmarks, the stretch curves, Python. Readers
// never reach into a term or the projection and never evaluate anything themselves.
//
// Convention (as MuJoCo's mjData after mj_step): the force records (energies, per-term
// forces, the contact set, kinetic energy, max |C|) describe the state the simulator's
// last `forward` saw — after a step, the state that step produced (each step ends by
// evaluating the forces at its result, which the next step reuses as its first
// evaluation, so no evaluation is added). The step records (projection statistics,
// constraint multipliers and forces, timings, warnings) describe the step that produced
// that state.
#include <Eigen/Core>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace knit {

/// One term's share of the forces at the recorded state.
struct TermRecord {
  std::string name;                                     ///< "gravity", "bending", "contact", …
  double energy = 0;                                    ///< potential energy (erg; 0 for damping)
  Eigen::Vector3d net_force = Eigen::Vector3d::Zero();  ///< Σ over control points (dyn)
};

/// A pair of segments in contact: the closest of their contact point pairs in contact.
struct ContactPairRecord {
  int seg_i = 0, seg_j = 0;  ///< global segment indices, seg_i < seg_j
  double d = 0;              ///< smallest |Δy| / 2r over the pair's point pairs (< 1)
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< unit, from y_i to y_j at that pair
  /// normal component of the contact force (elastic + damping, dyn) that segment i exerts
  /// on segment j, normal · Σ F_j; positive when it pushes the yarns apart
  double normal_force = 0;
  /// the curve parameters of that closest point pair on segment i and on segment j (its
  /// contact quadrature abscissae, in [0, 1]): y_j(t_j) − y_i(t_i) = 2r d · normal
  double t_i = 0, t_j = 0;
};

/// Yarn–yarn contact at the recorded state (absent when contact is off).
struct ContactRecord {
  bool present = false;
  long long candidate_segment_pairs = 0;
  long long point_pairs_tested = 0;
  long long point_pairs_in_contact = 0;
  /// smallest d over non-neighbouring point pairs within the contact distance; +inf if none
  double min_distance_ratio = std::numeric_limits<double>::infinity();
  bool candidates_rebuilt = false;
  /// the state's contact force is the linearised model of an earlier exact evaluation
  /// (SolverSettings::contact_reuse); the counts and pairs are that evaluation's
  bool linearised = false;
  std::vector<ContactPairRecord> pairs;  ///< segment pairs in contact, by (seg_i, seg_j)
  /// the contact term's exact evaluation (its count) that `pairs` was built from, −1 none:
  /// a linearised state's record keeps the list of the evaluation it comes from
  long long pairs_of = -1;
};

/// Yarn against one solid object (objects/object.hpp) at the recorded state: what the
/// penalty term found at the state, and what the collision filter found and did in the
/// step that produced it.
struct ObjectRecord {
  std::string name;
  /// yarn points within r of the surface (φ < r): the penalty's quadrature points plus
  /// the filter's sample points
  long long points_in_contact = 0;
  /// largest r − φ over those points (cm): how far the yarn's tube overlaps the object
  /// (0 when nothing touches; the centreline is inside the object when it exceeds r)
  double deepest_penetration = 0;
  /// force on the yarn (dyn): the penalty's at the state plus the filter's impulse / h
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
};

/// What one constraint group did in the last step (MODEL.md §5.2). With Λ the group's
/// multipliers summed over the projection's iterations (q ← q − M⁻¹ ∇Cᵀ δλ), the
/// projection moved the control points by −M⁻¹ ∇Cᵀ Λ, i.e. changed their momentum by
/// −∇Cᵀ Λ / h: the group exerted the generalised force F = −∇Cᵀ Λ / h² over the step.
struct ConstraintRecord {
  std::string name;  ///< "length", "pin0", "glue1", a clamp's name
  std::string kind;  ///< "length", "pin", "glue", "clamp"
  int rows = 0;
  Eigen::VectorXd multipliers;  ///< Λ per row (g·cm for point rows, g·cm² for length rows)
  /// Σ_k F_k over the control points (dyn): the total force the group exerts on the yarns.
  /// A glue's two points feel opposite forces; its `force` is the one on point a. Zero
  /// (not summed) for the length group, which exerts no net force or torque.
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  /// Σ_k (q_k − about) × F_k (dyn·cm); exact for point rows, whose F is B(t)-weighted.
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();
  Eigen::Vector3d about = Eigen::Vector3d::Zero();  ///< torque reference point (cm)
  double max_violation = 0;                         ///< max |C| over the rows after the step
};

/// What yarn–yarn friction (filters/yarn_friction.hpp) did in the last step.
struct FrictionRecord {
  bool present = false;  ///< whether the simulation has yarn–yarn friction
  long long pairs = 0;   ///< segment pairs it acted on (the contact set of the step's start)
  long long stuck = 0;   ///< of them, those it stopped sliding (inside their cones)
  /// energy it dissipated over the step (erg, ≥ 0): Σ −λ · u_t over the pairs, each
  /// impulse times the sliding rate it left (0 for a pair it stopped)
  double work = 0;
  /// Σ |λ| / h over the pairs (dyn): the total friction force magnitude over the step
  double force = 0;
  int passes = 0;  ///< Gauss–Seidel sweeps it needed
};

/// The last projection.
struct ProjectionRecord {
  bool converged = true;
  int iterations = 0;
  double residual = 0;  ///< max |C| at the end (all groups)
};

struct StepData {
  long long steps = 0;  ///< steps taken by this simulator
  double time = 0;      ///< time of the recorded state (s)
  // --- force records, at the recorded state
  double kinetic_energy = 0;    ///< ½ vᵀ M v (erg)
  double potential_energy = 0;  ///< Σ term energies (erg)
  std::vector<TermRecord> terms;
  ContactRecord contact;
  std::vector<ObjectRecord> objects;  ///< one per object of the model, in its order
  double max_violation = 0;           ///< max |C| over every constraint group at the state
  /// The force residual at the state (cm/s²; Simulator::force_residual): NaN unless it
  /// was asked for (relaxations with the force-residual rest test ask at every check).
  double force_residual = std::numeric_limits<double>::quiet_NaN();
  /// Where the residual sits (with it): the control point with the largest net
  /// acceleration left unheld (cm/s²; −1 none) and the share of the residual's square
  /// (Σ m a²) that the 1 % of control points with the most hold. A relaxation near rest
  /// creeps in a few places (a 42×32 rib at R = 2.6: 64 % in 1 % of its points, single
  /// loops and the yarn's ends).
  struct ResidualPeak {
    int control_point = -1;   ///< global index; −1 none
    double acceleration = 0;  ///< cm/s²
    double top_share = 0;     ///< of Σ m a², in the top 1 % of control points
  } force_residual_peak;
  /// With the force residual: what each constraint group must exert to hold the state
  /// at rest (dyn; the static reactions, −∇Cᵀ Λ for the force the terms exert along the
  /// constraints' normals at v = 0). Empty unless the residual was asked for. At an
  /// equilibrium they are the clamps' and pins' loads, free of the damping and inertia
  /// that the step's records (`constraints`) carry.
  std::vector<ConstraintRecord> static_constraints;
  // --- step records, of the step that produced it
  ProjectionRecord projection;
  /// The IMEX_CONTACT step's conjugate-gradient solve: iterations, and the residual left
  /// relative to the right-hand side (0 and 0 for the other integrators).
  int solve_iterations = 0;
  double solve_residual = 0;
  /// The IMEX step reused the last step's matrix M + h² K (SolverSettings::contact_reuse).
  bool matrix_kept = false;
  /// The scale of the contact reuse distances the IMEX step ran with
  /// (Simulator::set_reuse_scale; 1 unless a relaxation widened them).
  double reuse_scale = 1;
  std::vector<ConstraintRecord> constraints;
  FrictionRecord friction;
  /// wall seconds per stage, summed since the simulator's timings were reset: each term's
  /// name, "projection", each filter's name, "record"
  std::map<std::string, double> stage_seconds;
  /// per-step notes that did not stop the step (e.g. the projection nearly ran out of
  /// iterations, yarns came closer than half the contact distance): a fixed text, then
  /// the step's numbers in parentheses (the summary counts steps by the fixed text)
  std::vector<std::string> warnings;

  /// The record of a term, or nullptr.
  const TermRecord* term(const std::string& name) const {
    for (const TermRecord& t : terms)
      if (t.name == name) return &t;
    return nullptr;
  }
  /// The record of an object, or nullptr.
  const ObjectRecord* object(const std::string& name) const {
    for (const ObjectRecord& o : objects)
      if (o.name == name) return &o;
    return nullptr;
  }
  /// The record of a constraint group, or nullptr.
  const ConstraintRecord* constraint(const std::string& name) const {
    for (const ConstraintRecord& c : constraints)
      if (c.name == name) return &c;
    return nullptr;
  }
  /// The static reaction of a constraint group (see static_constraints), or nullptr.
  const ConstraintRecord* static_constraint(const std::string& name) const {
    for (const ConstraintRecord& c : static_constraints)
      if (c.name == name) return &c;
    return nullptr;
  }
};

}  // namespace knit
