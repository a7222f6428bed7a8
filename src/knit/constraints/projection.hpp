#pragma once
// Fast projection onto the constraint manifold (MODEL.md §5.2; Goldenthal et al. 2007,
// Algorithm 1, lumped mass): repeat  (G M⁻¹ Gᵀ) δλ = C(q_j),  q_{j+1} = q_j − M⁻¹ Gᵀ δλ
// until max |C| < tolerance. Rows: one per segment (inextensibility, when enabled), three
// per pin (y(s) − p(time), cm), three per glue (y(a) − y(b), cm).
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "knit/model/model.hpp"

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
  /// Projects q in place; the result says whether max |C| reached the tolerance.
  ProjectionResult project(const Model& model, Eigen::VectorXd& q, double time);
  /// Largest |C_i| over the inextensibility rows alone (0 when there are none).
  static double max_length_violation(const Model& model, const Eigen::VectorXd& q);

 private:
  void update_jacobian(const Model& model, const Eigen::VectorXd& q);
  int m_len_rows = 0;
  int m_rows = 0;
  Eigen::SparseMatrix<double, Eigen::RowMajor> m_G;
  Eigen::SparseMatrix<double> m_A;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> m_solver;
  Eigen::Index m_pattern_nnz = -1;
  Eigen::VectorXd m_c, m_dlambda;
};

}  // namespace knit
