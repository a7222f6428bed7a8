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
#include <functional>
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
  /// `fixed` (ascending coordinates): unknowns whose value is given, not solved for — a
  /// clamp's control points, whose new velocity the clamp prescribes. Their rows and
  /// columns are taken out of the matrix (what they couple to goes to the right-hand side
  /// in solve) and replaced by the identity.
  bool factor(const Model& model, const std::vector<Matrix12d>& blocks, double h2,
              const std::vector<int>& fixed = {});
  /// The same with `extra(i, block)` adding more to segment i's block as it is assembled
  /// (the preconditioner's share of terms applied as operators), called for different
  /// segments at once; the blocks are then summed in parallel, four interleaved sets of
  /// segments one after another (segments four apart share no coordinate). `extra` is
  /// given a zero block to add into, and returns false where it added nothing (the block
  /// must then be left zero).
  using ExtraBlock = std::function<bool(int, Matrix12d&)>;
  bool factor(const Model& model, const std::vector<Matrix12d>& blocks, double h2,
              const std::vector<int>& fixed, const ExtraBlock& extra);
  /// Solves the factored system for `rhs` (size 3 × control points) into x. At a fixed
  /// coordinate rhs holds its given value, which x then has.
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const;
  /// solve's first half: y = L⁻¹ rhs (with the fixed coordinates' couplings moved to the
  /// right-hand side); backward(y) then gives solve's x. Between the two a caller may
  /// correct y (the glues' W μ: Simulator::imex_step).
  void solve_forward(const Eigen::VectorXd& rhs, Eigen::VectorXd& y) const;
  /// The two halves of solve for a right-hand side that is zero at every fixed coordinate
  /// (a constraint's column Jᵀ): forward solves L y = x in place, x zero before `first`
  /// (the solve starts there, which a column near a yarn's end makes short); backward
  /// solves Lᵀ x = y in place. A = L Lᵀ, so Jᵀ A⁻¹ J = Wᵀ W with W = L⁻¹ Jᵀ.
  void forward(Eigen::VectorXd& x, int first = 0) const;
  void backward(Eigen::VectorXd& x) const;
  using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  /// forward on every column of X at once (one pass over the factor; X row-major), each column k
  /// from its own first nonzero row `first[k]` (its input zero before it and after `last[k]`), and
  /// stopped where it has died away: once past last[k], when BAND + 1 rows in a row are all below
  /// `negligible` times the column's largest value so far, the rest of the column is set to exactly
  /// 0. Returns each column's end (rows ≥ end[k] are 0). A column of L⁻¹ Jᵀ decays along the yarn
  /// from where J touches it (M + h² K is dominated by its diagonal well enough), so a glue's
  /// column is a short stretch of the yarn around the points it ties; its products with a vector
  /// then cost that stretch, not the whole yarn.
  std::vector<int> forward_columns(RowMajorMatrix& X, const std::vector<int>& first,
                                   const std::vector<int>& last, double negligible) const;
  /// The fixed coordinates given in factor, in order.
  const std::vector<int>& fixed() const { return m_fixed_dofs; }
  /// What the fixed coordinates' own rows of the original matrix leave over at x:
  /// (A x − b)_d for each fixed d, in order, with b_d from `b_fixed` (the same order) — the
  /// force (times h) that held them to their given values.
  void fixed_residuals(const Eigen::VectorXd& x, const std::vector<double>& b_fixed,
                       std::vector<double>& out) const;

 private:
  int m_n = 0;
  // per fixed coordinate, its matrix entries with the free ones it coupled to
  struct Coupling {
    int dof;
    std::vector<std::pair<int, double>> entries;  // with the free coordinates
    std::vector<std::pair<int, double>> row;      // the whole original row in the band
  };
  std::vector<Coupling> m_fixed;
  std::vector<int> m_fixed_dofs;
  // lower band, column major: entry (i, j), j ≤ i ≤ j + BAND, at m_band[j * (BAND + 1) + i − j]
  std::vector<double> m_band;
  std::vector<double> m_inv_pivot;  // 1 / L(j, j)
};

}  // namespace knit
