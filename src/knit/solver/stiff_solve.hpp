#pragma once
// The linear system of the linearly implicit step: (M + h² K) Δv = b, with M the lumped
// mass and K the stiffness of the implicit terms, one 12×12 block per segment (Term::
// segment_stiffness). A segment couples the three coordinates of four consecutive control
// points, so the matrix is banded with half-bandwidth 11 (coordinates of control points
// at most three apart); yarns follow each other in the control-point order and never
// couple. Its Cholesky factor has the same band (no fill outside it): factoring costs
// about 66 multiply-adds per coordinate and solving 24, against several times that for a
// general sparse Cholesky (Eigen has no band solver; this one is tested against Eigen's
// dense LLT).
#include <Eigen/Core>
#include <vector>

#include "knit/model/model.hpp"
#include "knit/spline/basis.hpp"

namespace knit {

class StiffSolver {
 public:
  /// Half-bandwidth of the matrix: coordinates of control points at most 3 apart.
  static constexpr int BAND = 11;
  /// Assembles M + h2 · Σ blocks (h2 = h², s²) for `model` and factors it. Returns false
  /// when the matrix is not positive definite (a block was not semidefinite).
  bool factor(const Model& model, const std::vector<Matrix12d>& blocks, double h2);
  /// Solves the factored system for `rhs` (size 3 × control points) into x.
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const;

 private:
  int m_n = 0;
  // lower band, column major: entry (i, j), j ≤ i ≤ j + BAND, at m_band[j * (BAND + 1) + i − j]
  std::vector<double> m_band;
};

}  // namespace knit
