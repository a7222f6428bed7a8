#include "knit/solver/stiff_solve.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace knit {

namespace {
constexpr int W = StiffSolver::BAND + 1;  // stored entries per column
}

bool StiffSolver::factor(const Model& model, const std::vector<Matrix12d>& blocks, double h2,
                         const std::vector<int>& fixed) {
  return factor(model, blocks, h2, fixed, ExtraBlock{});
}

bool StiffSolver::factor(const Model& model, const std::vector<Matrix12d>& blocks, double h2,
                         const std::vector<int>& fixed, const ExtraBlock& extra) {
  m_n = model.num_dof();
  m_band.assign(static_cast<size_t>(m_n) * W, 0.0);
  double* a = m_band.data();
  for (int d = 0; d < m_n; ++d) a[d * W] = model.mass[d / 3];
  auto add_block = [&](int i, const Matrix12d& b) {
    const int base = 3 * model.seg_cp[i];
    for (int c = 0; c < 12; ++c)
      for (int r = c; r < 12; ++r) a[(base + c) * W + (r - c)] += h2 * b(r, c);
  };
  // segment i's block and its extra part: `e` holds what extra added to a zero block, and
  // is zero again after (the blocks are not copied; where extra adds once per entry, as the
  // contact's operator blocks do, the sums are those of adding it into a copy of the block)
  auto add_block_and_extra = [&](int i, Matrix12d& e) {
    if (!extra(i, e)) {
      add_block(i, blocks[i]);
      return;
    }
    const Matrix12d& b = blocks[i];
    const int base = 3 * model.seg_cp[i];
    for (int c = 0; c < 12; ++c)
      for (int r = c; r < 12; ++r) a[(base + c) * W + (r - c)] += h2 * (b(r, c) + e(r, c));
    e.setZero();
  };
  const int n_seg = model.num_seg();
  bool ascending = true;  // each segment's first control point after the one before's
  for (int i = 1; i < n_seg && ascending; ++i) ascending = model.seg_cp[i] > model.seg_cp[i - 1];
  if (!extra) {
    for (int i = 0; i < n_seg; ++i) add_block(i, blocks[i]);
  } else if (!ascending) {
    Matrix12d e = Matrix12d::Zero();
    for (int i = 0; i < n_seg; ++i) add_block_and_extra(i, e);
  } else {
    // segments i and i + 4 cover disjoint coordinates: each set writes disjoint columns
    for (int set = 0; set < 4; ++set)
      tbb::parallel_for(tbb::blocked_range<int>(0, (n_seg - set + 3) / 4, 64),
                        [&](const tbb::blocked_range<int>& r) {
                          Matrix12d e = Matrix12d::Zero();
                          for (int k = r.begin(); k < r.end(); ++k)
                            add_block_and_extra(set + 4 * k, e);
                        });
  }
  // the fixed coordinates: their couplings to the free ones kept for solve, then their
  // rows and columns replaced by the identity's
  m_fixed.clear();
  m_fixed_dofs = fixed;
  if (!fixed.empty()) {
    std::vector<char> is_fixed(m_n, 0);
    for (int d : fixed) is_fixed[d] = 1;
    auto entry = [&](int i, int j) -> double& {  // (i, j) of the symmetric matrix
      return i >= j ? a[static_cast<size_t>(j) * W + (i - j)]
                    : a[static_cast<size_t>(i) * W + (j - i)];
    };
    for (int d : fixed) {
      Coupling c{d, {}, {}};
      for (int j = std::max(0, d - BAND); j <= std::min(m_n - 1, d + BAND); ++j) {
        if (entry(j, d) == 0) continue;
        c.row.emplace_back(j, entry(j, d));
        if (!is_fixed[j]) c.entries.emplace_back(j, entry(j, d));
      }
      m_fixed.push_back(std::move(c));
    }
    for (int d : fixed) {
      for (int j = std::max(0, d - BAND); j <= std::min(m_n - 1, d + BAND); ++j) entry(j, d) = 0;
      entry(d, d) = 1;
    }
  }
  // band Cholesky, right looking: column j scaled by its pivot, then the trailing
  // triangle within the band updated by its outer product
  m_inv_pivot.resize(m_n);
  for (int j = 0; j < m_n; ++j) {
    double* col = a + static_cast<size_t>(j) * W;
    if (!(col[0] > 0)) return false;
    const double pivot = std::sqrt(col[0]);
    col[0] = pivot;
    const int m = std::min(BAND, m_n - 1 - j);
    const double inv = 1.0 / pivot;
    m_inv_pivot[j] = inv;  // the solves multiply (a division would lengthen their chain)
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
  solve_forward(rhs, x);
  backward(x);
}

void StiffSolver::solve_forward(const Eigen::VectorXd& rhs, Eigen::VectorXd& y) const {
  y = rhs;
  // the fixed coordinates' values: what they contribute to the free rows moves to the
  // right-hand side (their own rows are the identity)
  for (const Coupling& c : m_fixed)
    for (const auto& [j, value] : c.entries) y[j] -= value * rhs[c.dof];
  forward(y);
}

void StiffSolver::forward(Eigen::VectorXd& x, int first) const {
  const double* a = m_band.data();
  const double* inv = m_inv_pivot.data();
  // L y = b; the columns with a full band first, their length a constant (unrolled: the
  // same operations in the same order, in half the time of a loop of runtime length)
  double* y = x.data();
  int j = std::max(0, first);
  for (; j < m_n - BAND; ++j) {
    const double* col = a + static_cast<size_t>(j) * W;
    y[j] *= inv[j];
    const double yj = y[j];
#pragma GCC unroll 16
    for (int r = 1; r <= BAND; ++r) y[j + r] -= col[r] * yj;
  }
  for (; j < m_n; ++j) {
    const double* col = a + static_cast<size_t>(j) * W;
    y[j] *= inv[j];
    const int m = m_n - 1 - j;
    for (int r = 1; r <= m; ++r) y[j + r] -= col[r] * y[j];
  }
}

std::vector<int> StiffSolver::forward_columns(RowMajorMatrix& X, const std::vector<int>& first,
                                              const std::vector<int>& last,
                                              double negligible) const {
  const double* a = m_band.data();
  const int m_cols = static_cast<int>(X.cols());
  double* x = X.data();
  std::vector<int> end(m_cols, m_n);
  // columns in the order they start; `active` those started and not yet died away
  std::vector<int> order(m_cols);
  for (int k = 0; k < m_cols; ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](int p, int q) { return first[p] < first[q]; });
  std::vector<double> peak(m_cols, 0.0);
  std::vector<int> last_big(m_cols, 0);
  std::vector<int> active;
  active.reserve(m_cols);
  size_t next = 0;
  for (int j = 0; j < m_n; ++j) {
    while (next < order.size() && first[order[next]] <= j) {
      const int k = order[next++];
      active.push_back(k);
      last_big[k] = j;
    }
    if (active.empty()) {
      if (next == order.size()) break;
      j = std::max(j, first[order[next]]) - 1;
      continue;
    }
    const double* col = a + static_cast<size_t>(j) * W;
    double* xj = x + static_cast<size_t>(j) * m_cols;
    const double inv = m_inv_pivot[j];
    const int m = std::min(BAND, m_n - 1 - j);
    for (int k : active) {
      xj[k] *= inv;
      const double value = std::abs(xj[k]);
      peak[k] = std::max(peak[k], value);
      if (value > negligible * peak[k]) last_big[k] = j;
    }
    for (int r = 1; r <= m; ++r) {
      double* xr = xj + static_cast<size_t>(r) * m_cols;
      const double l = col[r];
      for (int k : active) xr[k] -= l * xj[k];
    }
    // a column whose last BAND + 1 rows are negligible, its input all behind it, has died
    // away: what those rows passed on to the next BAND rows is dropped with them
    for (size_t t = 0; t < active.size();) {
      const int k = active[t];
      if (j >= last[k] && j - last_big[k] >= BAND) {
        end[k] = j + 1;
        for (int r = 1; r <= m; ++r) xj[static_cast<size_t>(r) * m_cols + k] = 0;
        active[t] = active.back();
        active.pop_back();
      } else {
        ++t;
      }
    }
  }
  return end;
}

void StiffSolver::backward(Eigen::VectorXd& x) const {
  const double* a = m_band.data();
  const double* inv = m_inv_pivot.data();
  // Lᵀ x = y, each row's sum taken from its farthest coordinate in: x[j + 1], found just
  // before, enters last, so one multiply-add and the pivot's product lie between one
  // coordinate and the next (summed nearest first, all eleven lay on that chain)
  for (int j = m_n - 1; j >= 0; --j) {
    const double* col = a + static_cast<size_t>(j) * W;
    const int m = std::min(BAND, m_n - 1 - j);
    double s = x[j];
    for (int r = m; r >= 1; --r) s -= col[r] * x[j + r];
    x[j] = s * inv[j];
  }
}

void StiffSolver::fixed_residuals(const Eigen::VectorXd& x, const std::vector<double>& b_fixed,
                                  std::vector<double>& out) const {
  out.resize(m_fixed.size());
  for (size_t k = 0; k < m_fixed.size(); ++k) {
    double ax = 0;
    for (const auto& [j, value] : m_fixed[k].row) ax += value * x[j];
    out[k] = ax - b_fixed[k];
  }
}

}  // namespace knit
