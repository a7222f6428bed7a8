#include "knit/constraints/inextensibility.hpp"

#include <tbb/parallel_for.h>

#include <cmath>

#include "knit/model/model.hpp"

namespace knit {

double length_constraint(const Vector12d& x, double rest_length, const QuadratureTable& quad,
                         Vector12d* grad) {
  const double inv_l = 1.0 / rest_length;
  double len = 0;
  if (grad) grad->setZero();
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector3d d1 = combine(x, quad.db[k]);
    const double speed = std::sqrt(d1.squaredNorm() + 1e-24);
    len += quad.w[k] * speed;
    if (grad) scatter(*grad, quad.db[k], (-quad.w[k] * inv_l / speed) * d1);
  }
  return 1.0 - len * inv_l;
}

LengthGroup::LengthGroup(const Model& model) : ConstraintGroup("length"), m_rows(model.num_seg()) {}

LengthGroup::LengthGroup(const Model& model, std::vector<int> segments)
    : ConstraintGroup("length"), m_rows(static_cast<int>(segments.size())) {
  if (m_rows != model.num_seg()) m_segments = std::move(segments);  // else the identity
}

void LengthGroup::jacobian_structure(const Model& model,
                                     std::vector<Eigen::Triplet<double>>& entries) const {
  for (int r = 0; r < m_rows; ++r) {
    const int i = m_segments.empty() ? r : m_segments[r];
    for (int k = 0; k < 12; ++k) entries.emplace_back(r, 3 * model.seg_cp[i] + k, 1.0);
  }
}

void LengthGroup::evaluate(const Model& model, const Eigen::VectorXd& q, double time, double* c,
                           double* jacobian) const {
  tbb::parallel_for(tbb::blocked_range<int>(0, m_rows, 256), [&](const auto& r) {
    Vector12d g;
    for (int row = r.begin(); row < r.end(); ++row) {
      const int i = m_segments.empty() ? row : m_segments[row];
      const Vector12d x = gather_segment(q, model.seg_cp[i]);
      if (!jacobian) {
        c[row] = length_constraint(x, model.rest_length[i], model.quad, nullptr);
        continue;
      }
      c[row] = length_constraint(x, model.rest_length[i], model.quad, &g);
      // each row holds its 12 columns 3·cp … 3·cp+11 in ascending order
      for (int k = 0; k < 12; ++k) jacobian[12 * row + k] = g[k];
    }
  });
}

}  // namespace knit
