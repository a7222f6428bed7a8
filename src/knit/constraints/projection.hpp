#pragma once
// Fast projection onto the constraint manifold (MODEL.md §5.2; Goldenthal et al. 2007,
// Algorithm 1, lumped mass): repeat  (G M⁻¹ Gᵀ) δλ = C(q_j),  q_{j+1} = q_j − M⁻¹ Gᵀ δλ
// until max |C| < tolerance. The rows are the model's constraint groups', stacked in order
// (constraints/group.hpp): the projection knows nothing of what a group means. It sums
// each row's δλ over the iterations into Λ, from which each group's force and torque are
// reported (StepData's ConstraintRecord).
//
// Cost per iteration: one pass of the constraint kernel gives C and the rows of G at once;
// A = G M⁻¹ Gᵀ is assembled in parallel, already in the fill-reducing (AMD) order, straight
// into a pattern fixed at construction (per entry, a precomputed list of the products that
// make it); the symbolic factorisation is computed once; factorisation (in place, no
// allocation up to ≈16,000 rows, Eigen's stack limit) and solve are Eigen's SimplicialLDLT.
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <vector>

#include "knit/constraints/group.hpp"
#include "knit/model/model.hpp"
#include "knit/model/step_data.hpp"

namespace knit {

struct ProjectionResult {
  bool converged = true;
  int iterations = 0;
  double max_violation = 0;  ///< max |C| at the end
};

class FastProjection {
 public:
  explicit FastProjection(const Model& model);
  int num_constraints() const { return m_rows; }
  /// C(q) at `time` (pins move with time).
  void evaluate(const Model& model, const Eigen::VectorXd& q, double time, Eigen::VectorXd& c);
  /// max |C(q)|.
  double max_violation(const Model& model, const Eigen::VectorXd& q, double time);
  /// Projects q in place; the result says whether max |C| reached the tolerance. The
  /// multipliers Λ (summed over the iterations) are kept for record_groups(). With
  /// `at_least_once` it solves for Λ once even when max |C| is already within the
  /// tolerance (a static reaction from a displacement smaller than the tolerance).
  ProjectionResult project(const Model& model, Eigen::VectorXd& q, double time,
                           bool at_least_once = false);
  /// One record per constraint group of the last project(): Λ, max |C| after it, and the
  /// force and torque −∇Cᵀ Λ / h² the group exerted over a step of h seconds, with ∇C as
  /// last evaluated and torques about the group's point at (q, time).
  void record_groups(const Model& model, const Eigen::VectorXd& q, double time, double h,
                     std::vector<ConstraintRecord>& records) const;
  /// Largest |C_i| over the inextensibility rows alone (0 when there are none).
  static double max_length_violation(const Model& model, const Eigen::VectorXd& q);

 private:
  // one term G_rk G_ck / m_k of an entry of A: value indices into G, and the dof k
  struct NormalTerm {
    int ga, gb, k;
  };
  void evaluate_impl(const Model& model, const Eigen::VectorXd& q, double time, Eigen::VectorXd& c,
                     bool jacobian);
  void build_normal_pattern(int num_dof);
  void assemble_normal_matrix(const Model& model);
  int m_rows = 0;
  std::vector<int> m_group_row;  // first row of each group (and m_rows at the end)
  Eigen::VectorXd m_lambda;      // Λ of the last projection
  Eigen::SparseMatrix<double, Eigen::RowMajor> m_G;
  // Â = P G M⁻¹ Gᵀ Pᵀ (+ ridge), upper triangle, fixed pattern; P is the AMD ordering
  Eigen::SparseMatrix<double> m_A;
  std::vector<int> m_perm;           // row r of A is row m_perm[r] of Â
  std::vector<NormalTerm> m_terms;   // the terms of every entry of m_A, entry by entry
  std::vector<int> m_term_begin;     // entry e's terms: [m_term_begin[e], [e + 1])
  std::vector<Eigen::Index> m_diag;  // value index of Â_cc
  // already ordered: factorises Â in place (no copy per factorisation)
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>>
      m_solver;
  bool m_analyzed = false;
  Eigen::VectorXd m_cperm, m_xperm;
  Eigen::VectorXd m_c, m_dlambda;
};

}  // namespace knit
