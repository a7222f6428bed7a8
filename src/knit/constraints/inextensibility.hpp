#pragma once
// Inextensibility constraint, one scalar per segment (MODEL.md §5.1, paper eq. 5):
//   C_i = 1 − (1/ℓ_i) ∫₀¹ |y_i'(t)| dt      (dimensionless)
// Its multiplier λ_i (g·cm², summed over a step's projection iterations) is the segment's
// tension impulse: the force along the yarn is of order λ_i / (ℓ_i h²).
#include <vector>
#include "knit/constraints/group.hpp"

#include "knit/spline/basis.hpp"

namespace knit {

/// C_i for control points `x`; writes ∂C_i/∂x into *grad (overwrites) when non-null.
double length_constraint(const Vector12d& x, double rest_length, const QuadratureTable& quad,
                         Vector12d* grad);

/// C_i of `rows` segments at q, in parallel and four at a time (one per SIMD lane, the same
/// formula as length_constraint): segment `segments[row]` for each row, or segment `row`
/// when `segments` is empty. Writes c[row] and, when `grad` is non-null, ∂C_i/∂x of the
/// segment's 12 control-point coordinates at grad[12·row … 12·row + 11].
void length_constraints(const Model& model, const Eigen::VectorXd& q,
                        const std::vector<int>& segments, int rows, double* c, double* grad);

/// The segments' C_i as one group ("length"): every segment (row i = segment i), or the
/// given ones in order. Its rows exert no net force or torque on a yarn (arclength is
/// invariant under rigid motion).
class LengthGroup : public ConstraintGroup {
 public:
  explicit LengthGroup(const Model& model);
  LengthGroup(const Model& model, std::vector<int> segments);
  std::string_view kind() const override { return "length"; }
  int rows() const override { return m_rows; }
  void jacobian_structure(const Model& model,
                          std::vector<Eigen::Triplet<double>>& entries) const override;
  bool jacobian_varies() const override { return true; }
  bool exerts_net_force() const override { return false; }
  void evaluate(const Model& model, const Eigen::VectorXd& q, double time, double* c,
                double* jacobian) const override;

 private:
  int m_rows = 0;
  std::vector<int> m_segments;  // empty: every segment, row i = segment i
};

}  // namespace knit
