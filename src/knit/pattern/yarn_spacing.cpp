#include "knit/pattern/yarn_spacing.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

#include "knit/spline/basis.hpp"

namespace knit {

namespace {

// pushes go a little beyond the target so that the iterations end
constexpr double SEPARATION_OVERSHOOT = 1.02;
constexpr int SEPARATION_ITERATIONS = 200;

// The segments of the yarns whose control points `cp` holds one after the other (yarn y's
// n_y segments have n_y + 3 control points): segment g (counted over all yarns) of yarn
// yarn[g] starts at control point g + 3·yarn[g]. Neighbours are segments of one yarn next
// to each other.
struct Segments {
  std::vector<int> yarn;
  Segments(const Eigen::Matrix3Xd& cp, std::span<const int> yarn_segments) {
    if (yarn_segments.empty()) {
      yarn.assign(std::max<Eigen::Index>(cp.cols() - 3, 0), 0);
      return;
    }
    for (size_t y = 0; y < yarn_segments.size(); ++y)
      yarn.insert(yarn.end(), yarn_segments[y], static_cast<int>(y));
    assert(static_cast<Eigen::Index>(yarn.size() + 3 * yarn_segments.size()) == cp.cols());
  }
  int count() const { return static_cast<int>(yarn.size()); }
  int first_control_point(int g) const { return g + 3 * yarn[g]; }
  bool neighbours(int g, int h) const { return yarn[g] == yarn[h] && std::abs(g - h) <= 1; }
};

Eigen::Matrix3Xd contact_points(const Eigen::Matrix3Xd& cp, const Segments& seg, int per) {
  const int nseg = seg.count();
  Eigen::Matrix3Xd x(3, nseg * per);
  for (int i = 0; i < nseg; ++i)
    for (int k = 0; k < per; ++k)
      x.col(i * per + k) =
          cp.middleCols<4>(seg.first_control_point(i)) * bspline_basis((k + 0.5) / per);
  return x;
}

// Points sorted by the cell of a uniform grid, to find the points near each one: all the
// points within one cell size lie in the 27 cells around it.
class PointGrid {
 public:
  PointGrid(const Eigen::Matrix3Xd& x, double cell) : m_cell(cell) {
    const int n = static_cast<int>(x.cols());
    m_cell_of.resize(n);
    m_keyed.resize(n);
    for (int a = 0; a < n; ++a) {
      m_cell_of[a] = (x.col(a) / cell).array().floor().cast<int>();
      m_keyed[a] = {key_of(m_cell_of[a]), a};
    }
    std::sort(m_keyed.begin(), m_keyed.end());
    m_ranges.reserve(n);
    for (int s = 0; s < n;) {
      int e = s;
      while (e < n && m_keyed[e].first == m_keyed[s].first) ++e;
      m_ranges[m_keyed[s].first] = {s, e};
      s = e;
    }
  }
  double cell() const { return m_cell; }
  // calls f(b) for every point b (a itself included) in the 27 cells around point a
  template <class F>
  void for_each_near(int a, F&& f) const {
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = m_ranges.find(key_of(m_cell_of[a] + Eigen::Vector3i(dx, dy, dz)));
          if (it == m_ranges.end()) continue;
          for (int s = it->second.first; s < it->second.second; ++s) f(m_keyed[s].second);
        }
  }

 private:
  static std::int64_t key_of(const Eigen::Vector3i& c) {
    const std::int64_t m = (1 << 20);
    return ((static_cast<std::int64_t>(c.x()) + m / 2) * m + (c.y() + m / 2)) * m + (c.z() + m / 2);
  }
  double m_cell;
  std::vector<Eigen::Vector3i> m_cell_of;
  std::vector<std::pair<std::int64_t, int>> m_keyed;
  std::unordered_map<std::int64_t, std::pair<int, int>> m_ranges;
};

// The closest pair of contact points of each pair of non-neighbouring segments that comes
// closer than `cutoff` (≤ the grid cell): (point a, point b) with a < b.
std::vector<std::pair<int, int>> close_pairs(const Eigen::Matrix3Xd& x, const Segments& seg,
                                             int per, double cutoff) {
  const PointGrid grid(x, cutoff);
  std::map<std::pair<int, int>, std::pair<double, std::pair<int, int>>> closest;
  for (int a = 0; a < x.cols(); ++a)
    grid.for_each_near(a, [&](int b) {
      if (b <= a || seg.neighbours(a / per, b / per)) return;
      const double d2 = (x.col(a) - x.col(b)).squaredNorm();
      if (d2 >= cutoff * cutoff) return;
      const auto key = std::make_pair(a / per, b / per);
      const auto it = closest.find(key);
      if (it == closest.end() || d2 < it->second.first) closest[key] = {d2, {a, b}};
    });
  std::vector<std::pair<int, int>> out;
  out.reserve(closest.size());
  for (const auto& [key, best] : closest) out.push_back(best.second);
  return out;
}

}  // namespace

// The loop model cannot keep every pair of yarns apart everywhere: where stitches change
// between knit and purl along the wale as well as along the course (seed, the seam of a
// tube in garter), a loop's head lies 2.2 D from its legs in depth and on its way passes
// within 0.8·2r of the legs of the loop above; and the fit cuts the corners of tight bends
// (a tube's tails, fewer segments per stitch than 8). This pass pushes apart
// the non-neighbouring contact points closer than `target`·2r, moving the control points
// of the two segments the least that moves the points apart (Jacobi iterations, each
// control point averaging the pushes it receives). It only ever separates, so the yarns
// keep the sides of each other they were laid on and the loops interlock as before.
void separate_close_pairs(Eigen::Matrix3Xd& cp, double radius, double target, int per,
                          std::span<const int> yarn_segments) {
  const Segments segs(cp, yarn_segments);
  const double want = target * 2 * radius;
  const int ncp = static_cast<int>(cp.cols());
  for (int it = 0; it < SEPARATION_ITERATIONS; ++it) {
    const Eigen::Matrix3Xd x = contact_points(cp, segs, per);
    const auto pairs = close_pairs(x, segs, per, want);
    if (pairs.empty()) return;
    Eigen::Matrix3Xd push = Eigen::Matrix3Xd::Zero(3, ncp);
    Eigen::VectorXd weight = Eigen::VectorXd::Zero(ncp);
    for (const auto& [a, b] : pairs) {
      const Eigen::Vector3d d = x.col(a) - x.col(b);
      const double dist = d.norm();
      if (!(dist > 0)) continue;
      // each side moves half the way to a little beyond the target
      const Eigen::Vector3d half = 0.5 * (SEPARATION_OVERSHOOT * want - dist) / dist * d;
      for (const auto& [point, sign] : {std::make_pair(a, 1.0), std::make_pair(b, -1.0)}) {
        const int seg = segs.first_control_point(point / per);
        const Eigen::Vector4d w = bspline_basis((point % per + 0.5) / per);
        for (int j = 0; j < 4; ++j) {
          // the least change moving the point: w_j·δ/|w|² (weighted by w_j in the average)
          push.col(seg + j) += sign * w[j] * w[j] / w.squaredNorm() * half;
          weight[seg + j] += w[j];
        }
      }
    }
    for (int j = 0; j < ncp; ++j)
      if (weight[j] > 0) cp.col(j) += push.col(j) / weight[j];
  }
}

MinDistance min_distance_brute_force(const Eigen::Matrix3Xd& cp, double radius, int per,
                                     std::span<const int> yarn_segments) {
  const Segments segs(cp, yarn_segments);
  const Eigen::Matrix3Xd x = contact_points(cp, segs, per);
  const int n = static_cast<int>(x.cols());
  MinDistance best;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      if (segs.neighbours(a / per, b / per)) continue;
      const double d2 = (x.col(a) - x.col(b)).squaredNorm();
      if (d2 < best_d2) best_d2 = d2, best.segment_a = a / per, best.segment_b = b / per;
    }
  best.ratio = std::sqrt(best_d2) / (2 * radius);
  return best;
}

MinDistance min_distance(const Eigen::Matrix3Xd& cp, double radius, int per,
                         std::span<const int> yarn_segments) {
  const Segments segs(cp, yarn_segments);
  const Eigen::Matrix3Xd x = contact_points(cp, segs, per);
  const int n = static_cast<int>(x.cols());
  const PointGrid grid(x, 3 * radius);
  struct Best {
    double d2 = std::numeric_limits<double>::infinity();
    int a = -1, b = -1;
  };
  const Best best = tbb::parallel_reduce(
      tbb::blocked_range<int>(0, n, 256), Best{},
      [&](const tbb::blocked_range<int>& r, Best acc) {
        for (int a = r.begin(); a < r.end(); ++a)
          grid.for_each_near(a, [&](int b) {
            if (b <= a || segs.neighbours(a / per, b / per)) return;
            const double d2 = (x.col(a) - x.col(b)).squaredNorm();
            // ties broken by index so the result does not depend on the thread count
            if (d2 < acc.d2 ||
                (d2 == acc.d2 && std::make_pair(a, b) < std::make_pair(acc.a, acc.b)))
              acc = {d2, a, b};
          });
        return acc;
      },
      [](const Best& l, const Best& r) {
        if (r.d2 < l.d2 || (r.d2 == l.d2 && std::make_pair(r.a, r.b) < std::make_pair(l.a, l.b)))
          return r;
        return l;
      });
  if (best.a < 0 || best.d2 > grid.cell() * grid.cell())
    return min_distance_brute_force(cp, radius, per, yarn_segments);
  return {std::sqrt(best.d2) / (2 * radius), best.a / per, best.b / per};
}

}  // namespace knit
