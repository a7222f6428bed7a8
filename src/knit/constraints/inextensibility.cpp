#include "knit/constraints/inextensibility.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "knit/energy/lanes.hpp"
#include "knit/model/model.hpp"

namespace knit {

namespace {

// C = 1 − (1/ℓ) Σ_k w_k |y'(t_k)| and its gradient, for one segment (T = double) or four
// side by side (T = lanes::VecD): one formula for both
template <class T>
T length_constraint_t(const T x[12], T rest_length, const QuadratureTable& quad, T* grad) {
  const T inv_l = 1.0 / rest_length;
  T len{};
  if (grad)
    for (int c = 0; c < 12; ++c) grad[c] = T{};
  for (int k = 0; k < quad.size(); ++k) {
    const Eigen::Vector4d& db = quad.db[k];
    T d1[3];  // y'
    for (int c = 0; c < 3; ++c)
      d1[c] = db[0] * x[c] + db[1] * x[3 + c] + db[2] * x[6 + c] + db[3] * x[9 + c];
    const T speed = lanes::sqrt(d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2] + 1e-24);
    len += quad.w[k] * speed;
    if (!grad) continue;
    const T coef = -quad.w[k] * inv_l / speed;
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) grad[3 * a + c] += db[a] * (coef * d1[c]);
  }
  return 1.0 - len * inv_l;
}

// Kept out of line: inlined into the loop over groups of rows (GCC 12, -march=native on
// AVX-512), a row's C came out rounded differently with 1 and with 2 threads (by 1.6e-16,
// Projection.DoesNotDependOnThreadCount), the code the compiler made for a group depending
// on where in a thread's range of groups it fell.
[[gnu::noinline]] lanes::VecD length_constraint_lanes(const lanes::VecD x[12], lanes::VecD rest,
                                                      const QuadratureTable& quad,
                                                      lanes::VecD* grad) {
  return length_constraint_t<lanes::VecD>(x, rest, quad, grad);
}

}  // namespace

double length_constraint(const Vector12d& x, double rest_length, const QuadratureTable& quad,
                         Vector12d* grad) {
  return length_constraint_t<double>(x.data(), rest_length, quad, grad ? grad->data() : nullptr);
}

void length_constraints(const Model& model, const Eigen::VectorXd& q,
                        const std::vector<int>& segments, int rows, double* c, double* grad) {
  using lanes::LANES;
  using lanes::VecD;
  const int groups = (rows + LANES - 1) / LANES;
  tbb::parallel_for(tbb::blocked_range<int>(0, groups, 64), [&](const tbb::blocked_range<int>& r) {
    for (int group = r.begin(); group < r.end(); ++group) {
      VecD x[12], g[12], rest;
      for (int l = 0; l < LANES; ++l) {
        // a last partial group repeats its last row in the spare lanes
        const int row = std::min(group * LANES + l, rows - 1);
        const int i = segments.empty() ? row : segments[row];
        const double* p = q.data() + 3 * model.seg_cp[i];
        for (int k = 0; k < 12; ++k) x[k][l] = p[k];
        rest[l] = model.rest_length[i];
      }
      const VecD values = length_constraint_lanes(x, rest, model.quad, grad ? g : nullptr);
      for (int l = 0; l < LANES && group * LANES + l < rows; ++l) {
        const int row = group * LANES + l;
        c[row] = values[l];
        if (grad)
          for (int k = 0; k < 12; ++k) grad[12 * static_cast<size_t>(row) + k] = g[k][l];
      }
    }
  });
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
  // each row of the Jacobian holds its 12 columns 3·cp … 3·cp+11 in ascending order
  length_constraints(model, q, m_segments, m_rows, c, jacobian);
}

}  // namespace knit
