#include "knit/contact/crossings.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "knit/contact/bvh.hpp"
#include "knit/model/model.hpp"
#include "knit/spline/basis.hpp"

namespace knit {

namespace {

double det3(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return a.dot(b.cross(c));
}

// c0 + c1 s + c2 s² + c3 s³
struct Cubic {
  double c[4];
  double operator()(double s) const { return c[0] + s * (c[1] + s * (c[2] + s * c[3])); }
};

// det[a1 − a0, b0 − a0, b1 − a0](s), each column linear in s: (x + s y)
Cubic coplanarity(const MovingEdge& a, const MovingEdge& b) {
  const Eigen::Vector3d u0 = a.p1 - a.p0, u1 = a.d1 - a.d0;
  const Eigen::Vector3d v0 = b.p0 - a.p0, v1 = b.d0 - a.d0;
  const Eigen::Vector3d w0 = b.p1 - a.p0, w1 = b.d1 - a.d0;
  Cubic f;
  f.c[0] = det3(u0, v0, w0);
  f.c[1] = det3(u1, v0, w0) + det3(u0, v1, w0) + det3(u0, v0, w1);
  f.c[2] = det3(u1, v1, w0) + det3(u1, v0, w1) + det3(u0, v1, w1);
  f.c[3] = det3(u1, v1, w1);
  return f;
}

// the parameters (u on a, v on b) where the two edges' lines come closest at step
// fraction s; false when the lines are (nearly) parallel
bool closest_parameters(const MovingEdge& a, const MovingEdge& b, double s, double& u, double& v) {
  const Eigen::Vector3d a0 = a.p0 + s * a.d0, a1 = a.p1 + s * a.d1;
  const Eigen::Vector3d b0 = b.p0 + s * b.d0, b1 = b.p1 + s * b.d1;
  const Eigen::Vector3d e = a1 - a0, g = b1 - b0, r = a0 - b0;
  const double ee = e.dot(e), gg = g.dot(g), eg = e.dot(g), er = e.dot(r), gr = g.dot(r);
  const double denom = ee * gg - eg * eg;
  if (!(denom > 1e-12 * ee * gg) || ee == 0 || gg == 0) return false;
  u = (eg * gr - er * gg) / denom;
  v = (ee * gr - eg * er) / denom;
  return true;
}

}  // namespace

std::vector<EdgeCrossing> edge_crossings(const MovingEdge& a, const MovingEdge& b) {
  const Cubic f = coplanarity(a, b);
  // the cubic is monotone between the roots of its derivative: split [0, 1] there
  std::array<double, 5> cuts{0, 1, 1, 1, 1};
  int n = 1;
  const double qa = 3 * f.c[3], qb = 2 * f.c[2], qc = f.c[1];
  auto add_cut = [&](double s) {
    if (s > 0 && s < 1) cuts[n++] = s;
  };
  if (qa != 0) {
    const double disc = qb * qb - 4 * qa * qc;
    if (disc > 0) {
      const double sq = std::sqrt(disc);
      // (the stable pair of quadratic roots)
      const double t = -0.5 * (qb + std::copysign(sq, qb));
      add_cut(t / qa);
      if (t != 0) add_cut(qc / t);
    }
  } else if (qb != 0) {
    add_cut(-qc / qb);
  }
  cuts[n++] = 1;
  std::sort(cuts.begin(), cuts.begin() + n);

  std::vector<EdgeCrossing> out;
  for (int k = 0; k + 1 < n; ++k) {
    double lo = cuts[k], hi = cuts[k + 1];
    const double flo = f(lo), fhi = f(hi);
    // a sign change inside (lo, hi]; a zero at a cut between two intervals is a touch (or
    // was counted as the end of the interval before, when it is the step's end)
    const bool ends_at_zero = fhi == 0 && hi == 1 && flo != 0;
    if (!(flo * fhi < 0) && !ends_at_zero) continue;
    double s = hi;
    if (!ends_at_zero) {
      const bool rising = flo < 0;
      for (int it = 0; it < 100 && hi - lo > 1e-15; ++it) {
        const double mid = 0.5 * (lo + hi);
        ((f(mid) < 0) == rising ? lo : hi) = mid;
      }
      s = 0.5 * (lo + hi);
    }
    double u = 0, v = 0;
    if (!closest_parameters(a, b, s, u, v)) continue;
    constexpr double SLACK = 1e-9;
    if (u < -SLACK || u > 1 + SLACK || v < -SLACK || v > 1 + SLACK) continue;
    out.push_back({s, std::clamp(u, 0.0, 1.0), std::clamp(v, 0.0, 1.0)});
  }
  return out;
}

std::vector<SegmentCrossing> find_crossings(const Model& model, const Eigen::VectorXd& q0,
                                            const Eigen::VectorXd& q1, int samples_per_segment) {
  if (q0.size() != model.num_dof() || q1.size() != model.num_dof())
    throw std::invalid_argument("find_crossings: the states have " + std::to_string(q0.size()) +
                                " and " + std::to_string(q1.size()) + " coordinates, the model " +
                                std::to_string(model.num_dof()));
  if (samples_per_segment < 1 || samples_per_segment > 64)
    throw std::invalid_argument("find_crossings: samples_per_segment must be in [1, 64], got " +
                                std::to_string(samples_per_segment));
  const int nseg = model.num_seg();
  const int P = samples_per_segment;
  if (nseg < 2) return {};

  // the polyline points of every segment at both ends of the step
  std::vector<Eigen::Vector4d> basis(P + 1);
  for (int k = 0; k <= P; ++k) basis[k] = bspline_basis(static_cast<double>(k) / P);
  std::vector<Eigen::Vector3d> start(static_cast<size_t>(nseg) * (P + 1)),
      move(static_cast<size_t>(nseg) * (P + 1));
  std::vector<Aabb> boxes(nseg), edge_boxes(static_cast<size_t>(nseg) * P);
  tbb::parallel_for(0, nseg, [&](int i) {
    const Vector12d x0 = gather_segment(q0, model.seg_cp[i]);
    const Vector12d x1 = gather_segment(q1, model.seg_cp[i]);
    Aabb box;
    for (int k = 0; k <= P; ++k) {
      const Eigen::Vector3d a = combine(x0, basis[k]), b = combine(x1, basis[k]);
      start[static_cast<size_t>(i) * (P + 1) + k] = a;
      move[static_cast<size_t>(i) * (P + 1) + k] = b - a;
      box.extend(a);
      box.extend(b);
    }
    // (a swept edge lies in the hull of its end points' positions at both ends of the step)
    const double margin = 1e-9 * (1 + box.hi.cwiseAbs().maxCoeff());
    boxes[i] = box.grown(margin);
    for (int k = 0; k < P; ++k) {
      const size_t j = static_cast<size_t>(i) * (P + 1) + k;
      Aabb e;
      for (const size_t v : {j, j + 1}) {
        e.extend(start[v]);
        e.extend(Eigen::Vector3d(start[v] + move[v]));
      }
      edge_boxes[static_cast<size_t>(i) * P + k] = e.grown(margin);
    }
  });
  Bvh bvh;
  bvh.build(boxes);

  auto edge = [&](int seg, int k) {
    const size_t j = static_cast<size_t>(seg) * (P + 1) + k;
    return MovingEdge{start[j], start[j + 1], move[j], move[j + 1]};
  };
  tbb::enumerable_thread_specific<std::vector<SegmentCrossing>> found;
  tbb::parallel_for(0, nseg, [&](int i) {
    auto& mine = found.local();
    bvh.query(
        boxes[i],
        [&](int j) {
          if (model.neighbours(i, j)) return;
          SegmentCrossing first;
          first.step_fraction = 2;  // none yet
          for (int ka = 0; ka < P; ++ka) {
            const MovingEdge ea = edge(i, ka);
            const Aabb& box_a = edge_boxes[static_cast<size_t>(i) * P + ka];
            for (int kb = 0; kb < P; ++kb) {
              if (!box_a.overlaps(edge_boxes[static_cast<size_t>(j) * P + kb])) continue;
              const MovingEdge eb = edge(j, kb);
              for (const EdgeCrossing& c : edge_crossings(ea, eb)) {
                if (c.s >= first.step_fraction) continue;
                first.segment_a = i;
                first.segment_b = j;
                first.step_fraction = c.s;
                first.u_a = (ka + c.u) / P;
                first.u_b = (kb + c.v) / P;
                first.point =
                    ea.p0 + c.s * ea.d0 + c.u * (ea.p1 + c.s * ea.d1 - ea.p0 - c.s * ea.d0);
              }
            }
          }
          if (first.segment_a >= 0) mine.push_back(first);
        },
        i);
  });
  std::vector<SegmentCrossing> out;
  for (auto& v : found) out.insert(out.end(), v.begin(), v.end());
  std::sort(out.begin(), out.end(), [](const SegmentCrossing& x, const SegmentCrossing& y) {
    return std::pair(x.segment_a, x.segment_b) < std::pair(y.segment_a, y.segment_b);
  });
  return out;
}

}  // namespace knit
