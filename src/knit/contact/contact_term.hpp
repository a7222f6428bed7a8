#pragma once
// Yarn–yarn contact assembled over the whole model (MODEL.md §3 contact energy, §4 contact
// damping, §7 culling; Kaldor, James & Marschner 2008, §4.2, §4.3 and §5.4). The pair
// formulas, units and the damping convention are in contact_kernel.hpp. The class is
// defined in three files: contact_term.cpp (evaluation, the contact points, the records and
// the brute-force oracle), contact_pairs.cpp (the BVH traversal and the pair kernel) and
// contact_reuse.cpp (the linearised reuse and the operator stiffness).
//
// Pairs: every pair of segments that are not Model::neighbours (same yarn, |i − j| ≤ 1);
// across yarns every pair. Each pair is evaluated once (i < j).
//
// Culling (ContactCulling::BVH). Each evaluation:
//   1. points: every segment's contact quadrature points y_i(t_a) and velocities v_i(t_a)
//      are tabulated, and the segment's box is the box of its points grown by r;
//   2. refit: a BVH over the segment boxes, built once (first evaluation) and refit after;
//   3. traverse: every segment queries the tree with its own box grown by δ/2 (in
//      parallel) and keeps the overlapping non-neighbour segments, sorted — the candidate
//      segment pairs. This list is kept (Verlet-list style) across evaluations — both
//      midpoint evaluations of a step and following steps — until some contact point has
//      moved more than δ/2 along some axis since it was built (δ = candidate_margin());
//   4. kernel: for each candidate pair (i < j) whose current boxes overlap, only the points of i
//   inside box_j grown by
//      r (and of j inside box_i grown by r) can be within 2r of the other segment; those
//      point pairs are tested densely and the pair's forces are stored if any is in contact;
//   5. gather: every segment sums its pair forces in a fixed order, then every control
//      point sums its ≤ 4 segments (SegmentAccumulator).
//
// Why a kept candidate list gives the same result, bitwise, as a fresh one. Let P_i be the
// contact points of segment i now, P_i⁰ when the list was built, and box(X) the bounding
// box of X. The list holds every non-neighbour pair whose boxes box(P⁰)+r+δ/2 overlap.
// While every point moved by at most δ/2 along each axis, box(P_i) ⊂ box(P_i⁰)+δ/2, so
// every pair whose current boxes box(P)+r overlap is still in the list. A point pair
// closer than 2r lies in overlapping current boxes, so no contact is missed; a listed
// pair whose current boxes do not overlap is skipped before its kernel (on some axis its
// points are more than 2r apart, so it has no contact and would have produced nothing).
// The kernels of the remaining pairs, their order (row i, partners j ascending) and the
// gather are those of a fresh list, so forces, energy and counts are identical; only
// box_tests (0 when the list was kept) tells the two apart.
//
// No step accumulates across threads, so the result is bitwise independent of the thread
// count. Buffers are kept between evaluations, so the steady state does not allocate.
// ContactCulling::BRUTE_FORCE visits all pairs serially with the plain dense kernel: the
// test oracle, O(N²).
#include <Eigen/Core>
#include <array>
#include <limits>
#include <string_view>
#include <vector>

#include "knit/contact/bvh.hpp"
#include "knit/energy/segment_accumulator.hpp"
#include "knit/energy/term.hpp"

namespace knit {

enum class ContactCulling { BVH, BRUTE_FORCE };

/// What the last evaluation visited.
struct ContactStats {
  /// segment pairs whose point kernels were run (BVH: non-neighbour pairs i < j whose
  /// boxes overlap; brute force: every non-neighbour pair)
  long long candidate_segment_pairs = 0;
  /// point pairs whose distance was computed
  long long point_pairs_tested = 0;
  /// point pairs with d = |Δy|/2r < 1 (they contribute energy and force)
  long long point_pairs_in_contact = 0;
  /// smallest d over non-neighbouring point pairs; +inf when no pair is within the
  /// culling radius d < 1 (it does not depend on the culling method)
  double min_distance_ratio = std::numeric_limits<double>::infinity();
  /// BVH node boxes tested during the traversal (0 for brute force, and when the
  /// candidate list of an earlier evaluation was kept)
  long long box_tests = 0;
  /// whether this evaluation rebuilt the candidate list (BVH culling)
  bool candidates_rebuilt = false;
  /// whether this evaluation reused the last exact one's linearisation (see
  /// ContactTerm::add_force); the counts above are then that exact evaluation's
  bool linearised = false;
};

/// Wall-clock seconds of the stages of the last evaluation.
struct ContactTimings {
  double build = 0;     ///< BVH build (only on the first evaluation, else 0)
  double points = 0;    ///< tabulating points, velocities and segment boxes
  double refit = 0;     ///< BVH refit
  double traverse = 0;  ///< candidate segment pairs
  double kernel = 0;    ///< point-pair kernels
  double gather = 0;    ///< per-segment and per-control-point reduction
  double total = 0;
};

/// One contact quadrature point pair in contact: point a of segment i, point b of j, i < j.
struct ContactPointPair {
  int seg_i = 0, point_a = 0, seg_j = 0, point_b = 0;
  auto operator<=>(const ContactPointPair&) const = default;
};

/// Yarn–yarn contact energy and contact damping as a Term.
class ContactTerm : public Term {
 public:
  /// Largest supported Params::contact_points.
  static constexpr int MAX_CONTACT_POINTS = 64;
  /// Default candidate margin δ in yarn radii (see candidate_margin()), and the largest
  /// the margin grows to by itself.
  static constexpr double DEFAULT_MARGIN_RADII = 0.5;
  static constexpr double MAX_ADAPTIVE_MARGIN_RADII = 4.0;
  /// The list lifetimes (evaluations) outside which an adaptive margin grows or shrinks.
  static constexpr int MIN_LIST_EVALUATIONS = 3, MAX_LIST_EVALUATIONS = 12;

  /// Sizes the buffers for `model` (the BVH is built on the first evaluation). Throws
  /// std::invalid_argument if model.params.discretisation.contact_points exceeds
  /// MAX_CONTACT_POINTS.
  explicit ContactTerm(const Model& model, ContactCulling culling = ContactCulling::BVH);

  std::string_view name() const override { return "contact"; }

  /// Adds the contact force −∂E/∂q and the contact damping force −∂D/∂q̇ (dyn) into
  /// `force` and returns the contact energy E (erg). A model with a different number of
  /// segments than the last call gets a fresh BVH.
  ///
  /// Reuse (SolverSettings::contact_reuse ρ > 0, with the stiffness operator on). An exact
  /// evaluation at (q₀, v₀) keeps its force f₀, energy E₀ and per point pair in contact its
  /// Δ₀ and stiffness. While every control point stays within ρ r of q₀ (times the scale of
  /// set_reuse_scale), later evaluations run no kernels and return the first-order model
  /// around it instead (Kaldor, James and Marschner 2010 reuse linearised contact models
  /// over many steps), per point pair with
  /// u = J (q − q₀) and w = J (v − v₀) the changes of Δ and Δv:
  ///   F_j = F_j⁰ − H u + (damping's force of w with Δ₀'s normal),  F_i = −F_j
  ///   E = E₀ + Σ (−F_j⁰·u + ½ uᵀH u)
  /// with H the exact Hessian (ContactHessian::EXACT) of the pair's energy in Δ. The model
  /// misses pairs that come into contact after q₀ and keeps those that left, whose energy
  /// and force start from 0 at d = 1 (the force's derivative jumps there, so for such a
  /// pair the force's error is of first order in how far it crossed); the damping force
  /// keeps q₀'s normals (an error of the order of the motion times the velocity).
  /// Elsewhere the error is of second order in the motion. refresh() makes the next
  /// evaluation exact.
  double add_force(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                   double time, Eigen::VectorXd& force) override;
  void refresh() override { m_lin_valid = false; }
  /// The reuse distance becomes `scale` ρ r (Simulator::set_reuse_scale; 1 at first).
  void set_reuse_scale(double scale) override { m_reuse_scale = scale; }
  /// Evaluations that reused a linearisation (not counted in evaluations()).
  long long linearised_evaluations() const { return m_linearised; }

  ContactCulling culling() const { return m_culling; }
  /// The candidate margin δ (cm): candidate segment pairs are found with boxes grown by
  /// δ/2 and kept until a contact point has moved more than δ/2 along some axis. Larger
  /// margins rebuild less often and test more candidates; results do not depend on it.
  /// Unless set, δ adapts to the motion: it starts at DEFAULT_MARGIN_RADII radii and, at
  /// a rebuild, grows 1.5× (up to MAX_ADAPTIVE_MARGIN_RADII radii) when the list lasted
  /// fewer than MIN_LIST_EVALUATIONS evaluations, and shrinks 1.5× (down to the default)
  /// when it lasted more than MAX_LIST_EVALUATIONS.
  double candidate_margin() const { return m_margin; }
  /// Sets δ (cm, ≥ 0; 0 rebuilds whenever anything moved) and keeps it. Throws
  /// std::invalid_argument for a negative or non-finite margin.
  void set_candidate_margin(double margin);
  /// Evaluations so far, and how many of them rebuilt the candidate list.
  long long evaluations() const override { return m_evaluations; }
  long long candidate_rebuilds() const { return m_rebuilds; }
  /// Counts of the last evaluation.
  const ContactStats& last_stats() const { return m_stats; }
  /// Stage timings of the last evaluation.
  const ContactTimings& last_timings() const { return m_timings; }

  /// The counters and, for BVH culling, the segment pairs in contact of the last
  /// evaluation (brute force leaves the pair list empty).
  void record(StepData& data) const override;

  /// The contact energy's Hessian made semidefinite (ContactHessian::MIRRORED: per point
  /// pair in contact, its normal stiffness c f''(d)/(2r)² along n̂ and the absolute value
  /// of its transverse one across) as an operator, for the
  /// IMEX_CONTACT integrator. Needs BVH culling (std::logic_error otherwise).
  bool has_operator_stiffness() const override { return true; }
  void set_operator_stiffness(bool on) override;
  /// y += K x for the point pairs in contact at the last evaluation (in parallel, in a
  /// fixed order: the result does not depend on the thread count). Where x is bitwise the
  /// velocity of the last evaluation (with damping on), the kernels formed K x already
  /// and it is added as it stands.
  void add_stiffness_product(const Model& model, const Eigen::VectorXd& x,
                             Eigen::VectorXd& y) const override;
  void add_stiffness_product_rows(const Model& model, const Eigen::VectorXd& x,
                                  const std::vector<int>& segments,
                                  Eigen::VectorXd& y) const override;
  /// Per point pair, (B_a B_aᵀ) ⊗ H into segment i's block and (B_b B_bᵀ) ⊗ H into j's,
  /// H = k n̂n̂ᵀ + kt (I − n̂n̂ᵀ): the operator without its coupling of i to j.
  void add_operator_segment_stiffness(const Model& model,
                                      std::vector<Matrix12d>& blocks) const override;
  bool add_operator_segment_block(const Model& model, int segment, Matrix12d& block) const override;

  /// When on, each evaluation records its point pairs in contact (slow; for tests).
  void set_record_point_pairs(bool on) { m_record = on; }
  /// The point pairs in contact of the last evaluation with recording on, sorted.
  const std::vector<ContactPointPair>& last_point_pairs() const { return m_point_pairs; }

 private:
  // forces of one segment pair (i < j) that has at least one point pair in contact
  struct PairForce {
    int j = 0;
    Vector12d force_i, force_j;
    double min_d2 = 0;             // smallest squared distance of a point pair in contact (cm²)
    Eigen::Vector3d delta;         // y_j − y_i at that point pair (cm)
    int point_a = 0, point_b = 0;  // its contact points on i and on j
    int stiff_begin = 0, stiff_end = 0;  // its point pairs in m_row_stiff[i] (m_stiffness)
    int sj_begin = 0, sj_end = 0;        // its sums at j's points in m_row_sj[i] (m_stiffness)
  };
  // a point pair in contact of row i's segment pair (i, j): its points, Δ = y_j(t_b) −
  // y_i(t_a) (cm), and its stiffness kn ΔΔᵀ + kt I: kn = (k − kt)/|Δ|² with the normal
  // stiffness k = c f''(d)/(2r)² and the transverse one kt = c |f'(d)|/(2r |Δ|) (dyn/cm;
  // ContactHessian::MIRRORED)
  struct StiffPair {
    int j = 0, a = 0, b = 0;
    double dx = 0, dy = 0, dz = 0, kn = 0, kt = 0;
  };
  // a StiffPair as the products and the linearisation read it, all rows' in one array
  // (index_incoming_pairs): the first control points ci of segment i and cj of j, and the
  // damping's factor c2 = −2 ℓ_i ℓ_j w_a w_b (cm²); one cache line
  struct FlatPair {
    int ci = 0, cj = 0, a = 0, b = 0;
    double dx = 0, dy = 0, dz = 0, kn = 0, kt = 0, c2 = 0;
  };
  // an incoming point pair of a segment (it is j): its index in m_flat, and its point on j
  struct IncomingPoint {
    int k = 0, b = 0;
  };
  // the six numbers (xx, xy, xz, yy, yz, zz) of the sum of point pairs' stiffnesses at one
  // contact point of a segment (dyn/cm)
  struct PointStiffness {
    int point = 0;
    std::array<double, 6> s{};
  };
  // a row's sums at its own segment's points over all its pairs (pair_kernel's scratch)
  struct OwnStiffness {
    std::array<std::array<double, 6>, MAX_CONTACT_POINTS> s;
    std::array<char, MAX_CONTACT_POINTS> used;
  };

  // a segment pair's share of K v, v the evaluation's velocity (m_stiffness with damping)
  struct PairKv {
    Vector12d i, j;  // on segment i's control points and on j's (dyn)
  };
  // per-segment (row) outputs of the kernel stage
  struct RowStats {
    double energy = 0;
    long long candidates = 0, tested = 0, contacts = 0, box_tests = 0;
    double min_d2 = std::numeric_limits<double>::infinity();  // squared distance (cm²)
  };

  void resize(const Model& model);
  // segment s's operator block as its 10 upper 3×3 blocks (u, v ≥ u in order; each
  // symmetric, xx xy xz yy yz zz); false where it is zero
  bool operator_block_upper(int s, double (*upper)[6]) const;
  // m_incoming from the kernels' pairs (rows 0 … n − 1), and with m_stiffness the rows'
  // point pairs numbered (m_stiff_offset)
  void index_incoming_pairs(int n);
  // with m_stiffness, the last evaluation's point pairs flattened (m_flat, m_in_points),
  // once per evaluation, by the first reader
  void flatten(const Model& model) const;
  // the stiffness product's force of point pair p, H (J x), from x at its segments' control
  // points (p.ci, p.cj)
  Eigen::Vector3d pair_product(const FlatPair& p, const double* x) const;
  // segment s's 12 entries of K x from each point pair's force(k) (k: its index in
  // m_flat): its own row's pairs (it is i), then the pairs of rows k < s that have it as j,
  // in ascending k (Slot: Vector12d with a Vector3d per pair, or 12×2 with a 3×2, two
  // products at once)
  template <class Force, class Slot>
  void segment_product(int s, Force&& force, Slot& slot) const;
  void tabulate_points(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v);
  template <bool DAMP, bool STIFF>
  void pair_kernel(const Model& model, int i, int j, RowStats& row, OwnStiffness& own);
  int points_inside(const Aabb& box, size_t base, int* out) const;
  double add_force_bvh(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                       Eigen::VectorXd& force);
  double add_force_brute(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                         Eigen::VectorXd& force);
  // the linearised model of add_force around the last exact evaluation (m_lin_*)
  double add_force_linearised(const Model& model, const Eigen::VectorXd& q,
                              const Eigen::VectorXd& v, Eigen::VectorXd& force);

  ContactCulling m_culling;
  int m_num_seg = 0;
  double m_radius = 0;
  int m_points = 0;
  bool m_has_velocity = false;
  bool m_record = false;
  bool m_stiffness = false;
  // contact points and velocities, structure of arrays, index segment·P + a
  std::vector<double> m_px, m_py, m_pz, m_vx, m_vy, m_vz;
  std::vector<std::array<double, 4>> m_basis;  // B_0..3(t_a) per contact point
  std::vector<double> m_abscissae;             // t_a per contact point
  std::vector<Aabb> m_boxes;
  Bvh m_bvh;
  std::vector<std::vector<int>> m_partners;  // per segment: candidates, sorted
  // the candidate list: margin δ, points and grown boxes when it was built, and how far
  // the points moved since (largest per-axis displacement, per segment and overall)
  double m_margin = 0;
  bool m_margin_adaptive = true;
  bool m_list_valid = false;
  double m_list_margin = 0;       // δ of the current list
  long long m_list_built_at = 0;  // m_evaluations when it was built
  const Model* m_list_model = nullptr;
  double m_list_radius = 0;
  double m_list_moved = 0;
  long long m_evaluations = 0, m_rebuilds = 0;
  std::vector<double> m_lx, m_ly, m_lz, m_seg_moved;
  std::vector<Aabb> m_list_boxes;
  std::vector<long long> m_list_box_tests;
  std::vector<std::vector<PairForce>> m_pairs;  // per segment i: pairs (i, j > i) in contact
  // per segment s: the pairs (k < s, s) in contact, m_pairs[k][index], in ascending k, at
  // [m_incoming_offset[s], m_incoming_offset[s + 1]) (built after the kernels by a counting
  // sort, so that the gather visits only pairs in contact rather than search every
  // candidate)
  struct Incoming {
    int k = 0, index = 0;
  };
  std::vector<Incoming> m_incoming;
  std::vector<int> m_incoming_offset, m_incoming_fill;
  // with m_stiffness, the rows' point pairs stay in m_row_stiff; row i's are numbered
  // [m_stiff_offset[i], m_stiff_offset[i + 1]) (the index of their products), and are
  // copied in that order to m_flat; segment s's incoming ones, in segment_product's
  // order, are m_in_points[m_in_offset[s] … m_in_offset[s + 1]). The products and the
  // linearisation run over these flat arrays: a knit's rows hold a few point pairs each,
  // and reading them row by row from their own vectors was mostly waiting for memory
  std::vector<int> m_stiff_offset;
  mutable std::vector<FlatPair> m_flat;
  mutable std::vector<IncomingPoint> m_in_points;
  mutable std::vector<int> m_in_offset;
  mutable bool m_flat_valid = false;  // m_flat, m_in_points describe the last evaluation
  mutable std::vector<Eigen::Vector3d> m_stiff_product;  // per point pair: H (J x) (dyn)
  std::vector<RowStats> m_rows;
  std::vector<std::vector<ContactPointPair>> m_row_records;
  std::vector<std::vector<StiffPair>> m_row_stiff;  // per row i, with m_stiffness
  // per row i, beside m_pairs[i]: K v of its pairs; their sum per control point m_kv, and
  // the v it was formed with (add_stiffness_product of that v returns it)
  std::vector<std::vector<PairKv>> m_row_kv;
  SegmentAccumulator m_kv_accumulator;
  Eigen::VectorXd m_kv, m_kv_velocity;
  bool m_kv_valid = false;
  // with m_stiffness, per row i: the sums at segment i's contact points over its pairs, and
  // per pair (PairForce::sj_begin …) at segment j's (add_operator_segment_block adds them)
  std::vector<std::vector<PointStiffness>> m_row_si, m_row_sj;
  // add_stiffness_product: the per-segment sums
  mutable SegmentAccumulator m_product_accumulator;
  std::vector<ContactPointPair> m_point_pairs;
  mutable std::vector<long long> m_record_offset;  // record(): first pair of each row
  SegmentAccumulator m_accumulator;
  ContactStats m_stats;
  ContactTimings m_timings;
  // reuse: the last exact evaluation's state, force and energy (add_force), the change
  // from it, and per point pair (numbered as m_stiff_offset) the model's force change
  bool m_lin_valid = false;
  double m_reuse_scale = 1;  // set_reuse_scale
  const Model* m_lin_model = nullptr;
  Eigen::VectorXd m_lin_q, m_lin_v, m_lin_force, m_lin_dq, m_lin_dv, m_lin_kv0;
  bool m_lin_kv_valid = false;  // m_lin_kv0 = K v₀ (the kernels formed it)
  double m_lin_energy = 0;
  long long m_linearised = 0;
  // per point pair: the force change on j and, with K v fused, K (v − v₀)'s share
  std::vector<Eigen::Matrix<double, 3, 2>> m_lin_pair_force;
  std::vector<double> m_lin_row_energy;
  // while reusing: per segment its operator block's upper 3×3s (operator_block_upper, 60
  // numbers), formed on the first request after an exact evaluation (state 0 not yet, 1
  // zero, 2 kept)
  mutable std::vector<double> m_block_cache;
  mutable std::vector<char> m_block_state;
};

}  // namespace knit
