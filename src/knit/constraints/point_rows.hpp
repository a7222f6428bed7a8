#pragma once
// The constant ∇C of a point row block: y(s) = Σ_a B_a(t) x_{cp+a}, so ∂y(s)/∂x_{cp+a} =
// B_a(t) I. Shared by pins, glue and clamps.
#include <Eigen/SparseCore>
#include <vector>

#include "knit/model/model.hpp"

namespace knit {

/// Appends sign · ∂y(p)/∂q for rows row … row+2.
inline void add_point_rows(const Model& model, int row, const YarnPoint& p, double sign,
                           std::vector<Eigen::Triplet<double>>& entries) {
  const Eigen::Vector4d b = bspline_basis(p.t);
  for (int a = 0; a < 4; ++a)
    for (int c = 0; c < 3; ++c)
      entries.emplace_back(row + c, 3 * (model.seg_cp[p.segment] + a) + c, sign * b[a]);
}

}  // namespace knit
