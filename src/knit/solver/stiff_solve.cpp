#include "knit/solver/stiff_solve.hpp"

#include <algorithm>
#include <cmath>

namespace knit {

namespace {
constexpr int W = StiffSolver::BAND + 1;  // stored entries per column
}

bool StiffSolver::factor(const Model& model, const std::vector<Matrix12d>& blocks, double h2) {
  m_n = model.num_dof();
  m_band.assign(static_cast<size_t>(m_n) * W, 0.0);
  double* a = m_band.data();
  for (int d = 0; d < m_n; ++d) a[d * W] = model.mass[d / 3];
  for (int i = 0; i < model.num_seg(); ++i) {
    const Matrix12d& b = blocks[i];
    const int base = 3 * model.seg_cp[i];
    for (int c = 0; c < 12; ++c)
      for (int r = c; r < 12; ++r) a[(base + c) * W + (r - c)] += h2 * b(r, c);
  }
  // band Cholesky, right looking: column j scaled by its pivot, then the trailing
  // triangle within the band updated by its outer product
  for (int j = 0; j < m_n; ++j) {
    double* col = a + static_cast<size_t>(j) * W;
    if (!(col[0] > 0)) return false;
    const double pivot = std::sqrt(col[0]);
    col[0] = pivot;
    const int m = std::min(BAND, m_n - 1 - j);
    const double inv = 1.0 / pivot;
    for (int r = 1; r <= m; ++r) col[r] *= inv;
    for (int c = 1; c <= m; ++c) {
      double* next = a + static_cast<size_t>(j + c) * W;
      const double lc = col[c];
      for (int r = c; r <= m; ++r) next[r - c] -= col[r] * lc;
    }
  }
  return true;
}

void StiffSolver::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const {
  x = rhs;
  const double* a = m_band.data();
  // L y = b
  for (int j = 0; j < m_n; ++j) {
    const double* col = a + static_cast<size_t>(j) * W;
    x[j] /= col[0];
    const int m = std::min(BAND, m_n - 1 - j);
    for (int r = 1; r <= m; ++r) x[j + r] -= col[r] * x[j];
  }
  // Lᵀ x = y
  for (int j = m_n - 1; j >= 0; --j) {
    const double* col = a + static_cast<size_t>(j) * W;
    const int m = std::min(BAND, m_n - 1 - j);
    double s = x[j];
    for (int r = 1; r <= m; ++r) s -= col[r] * x[j + r];
    x[j] = s / col[0];
  }
}

}  // namespace knit
