#include "knit/filters/nonrigid_damping.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>

namespace knit {

RegionList small_stitch_regions(const Model& model) {
  std::map<std::pair<int, int>, std::vector<int>> loops;
  for (int i = 0; i < model.num_seg(); ++i)
    if (model.stitch[i].row >= 0) loops[{model.stitch[i].row, model.stitch[i].col}].push_back(i);
  RegionList regions;
  for (const auto& [rc, segs] : loops) {
    std::vector<int> region = segs;
    const auto below = loops.find({rc.first - 1, rc.second});
    if (below != loops.end())
      region.insert(region.end(), below->second.begin(), below->second.end());
    std::sort(region.begin(), region.end());
    regions.push_back(std::move(region));
  }
  return regions;
}

RegionList large_stitch_regions(const Model& model, int block, int stride, bool wrap_columns) {
  if (block < 1 || stride < 1)
    throw std::invalid_argument("large regions need block >= 1 and stride >= 1");
  int rows = 0, cols = 0;
  for (const StitchCoord& s : model.stitch)
    if (s.row >= 0) rows = std::max(rows, s.row + 1), cols = std::max(cols, s.col + 1);
  RegionList regions;
  const int first = -(block - stride) / stride * stride;
  // around a tube every block is whole: its columns run on past the last into the first
  const int col_first = wrap_columns ? 0 : first;
  auto in_columns = [&](int col, int c0) {
    if (!wrap_columns) return col >= std::max(c0, 0) && col < c0 + block;
    return ((col - c0) % cols + cols) % cols < std::min(block, cols);
  };
  for (int r0 = first; r0 < rows; r0 += stride)
    for (int c0 = col_first; c0 < cols; c0 += stride) {
      std::vector<int> region;
      for (int i = 0; i < model.num_seg(); ++i) {
        const StitchCoord& s = model.stitch[i];
        if (s.row >= std::max(r0, 0) && s.row < r0 + block && in_columns(s.col, c0))
          region.push_back(i);
      }
      if (!region.empty()) regions.push_back(std::move(region));
    }
  return regions;
}

RigidRegionPass::RigidRegionPass(const Model& model, RegionList regions, double alpha)
    : m_regions(std::move(regions)), m_alpha(alpha) {
  if (!(alpha >= 0 && alpha <= 1))
    throw std::invalid_argument("non-rigid damping strength alpha must lie in [0, 1], got " +
                                std::to_string(alpha));
  const int nseg = model.num_seg();
  std::vector<int> count(nseg, 0);
  for (size_t r = 0; r < m_regions.size(); ++r)
    for (int i : m_regions[r]) {
      if (i < 0 || i >= nseg)
        throw std::out_of_range("region " + std::to_string(r) + " names segment " +
                                std::to_string(i) + " (the model has " + std::to_string(nseg) +
                                " segments)");
      ++count[i];
    }
  m_seg_begin.assign(nseg + 1, 0);
  for (int i = 0; i < nseg; ++i) m_seg_begin[i + 1] = m_seg_begin[i] + count[i];
  m_seg_regions.resize(m_seg_begin[nseg]);
  std::vector<int> fill(m_seg_begin.begin(), m_seg_begin.end() - 1);
  for (size_t r = 0; r < m_regions.size(); ++r)
    for (int i : m_regions[r]) m_seg_regions[fill[i]++] = static_cast<int>(r);
}

double per_step_strength(double alpha, double h) {
  if (!(h > 0) || h == FILTER_REFERENCE_STEP) return alpha;
  return 1.0 - std::pow(1.0 - alpha, h / FILTER_REFERENCE_STEP);
}

// The rigid fit of a region needs only its mass moments, so each segment's samples are
// summed once (weights m_s / r(s), r = regions of this pass holding the segment), every
// region sums its segments' moments and shifts them to its centre (parallel-axis theorem),
// and every sample's target mean rigid velocity is A_i + B_i × x with per-segment A, B.
void RigidRegionPass::velocity_change(const SampleSegments& samples, const Eigen::Matrix3Xd& x,
                                      const Eigen::Matrix3Xd& u, Eigen::Matrix3Xd& dv,
                                      double strength) const {
  const double alpha = strength < 0 ? m_alpha : strength;
  const int per = samples.samples_per_segment();
  const int nseg = static_cast<int>(m_seg_begin.size()) - 1;
  auto share = [&](int seg) { return m_seg_begin[seg + 1] - m_seg_begin[seg]; };
  m_moments.resize(nseg);
  tbb::parallel_for(tbb::blocked_range<int>(0, nseg, 64),
                    [&](const tbb::blocked_range<int>& range) {
                      for (int i = range.begin(); i < range.end(); ++i) {
                        Moments& mo = m_moments[i];
                        mo.m = 0;
                        mo.mx.setZero();
                        mo.mu.setZero();
                        mo.xu.setZero();
                        mo.xx.setZero();
                        if (share(i) == 0) continue;
                        const double inv_share = 1.0 / share(i);
                        for (int k = 0; k < per; ++k) {
                          const int s = i * per + k;
                          const double w = samples.mass(s) * inv_share;
                          const Eigen::Vector3d xs = x.col(s), us = u.col(s);
                          mo.m += w;
                          mo.mx += w * xs;
                          mo.mu += w * us;
                          mo.xu += w * xs.cross(us);
                          mo.xx.noalias() += w * xs * xs.transpose();
                        }
                      }
                    });
  // rigid motion of every region, each computed alone from the same velocities
  m_fit.assign(m_regions.size(), RigidFit{});
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, m_regions.size(), 16),
      [&](const tbb::blocked_range<size_t>& range) {
        for (size_t r = range.begin(); r < range.end(); ++r) {
          Moments sum;
          sum.mx.setZero();
          sum.mu.setZero();
          sum.xu.setZero();
          sum.xx.setZero();
          for (int i : m_regions[r]) {
            const Moments& mo = m_moments[i];
            sum.m += mo.m;
            sum.mx += mo.mx;
            sum.mu += mo.mu;
            sum.xu += mo.xu;
            sum.xx += mo.xx;
          }
          if (!(sum.m > 0)) continue;
          RigidFit& f = m_fit[r];
          f.centre = sum.mx / sum.m;
          f.velocity = sum.mu / sum.m;
          // about the centre: L = Σw (x−c)×(u−v) = Σw x×u − c×Σw u,
          // I = tr(S)·1 − S with S = Σw (x−c)(x−c)ᵀ = Σw x xᵀ − m c cᵀ
          const Eigen::Vector3d l = sum.xu - f.centre.cross(sum.mu);
          const Eigen::Matrix3d spread = sum.xx - sum.m * f.centre * f.centre.transpose();
          const Eigen::Matrix3d inertia = spread.trace() * Eigen::Matrix3d::Identity() - spread;
          // ω = I⁺ L: eigen-directions with (relatively) no inertia get no spin
          const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(inertia);
          const double top = eig.eigenvalues().maxCoeff();
          for (int a = 0; a < 3; ++a) {
            const double lambda = eig.eigenvalues()[a];
            if (lambda > 1e-10 * top) {
              const Eigen::Vector3d e = eig.eigenvectors().col(a);
              f.omega += e * (e.dot(l) / lambda);
            }
          }
        }
      });
  // every sample moves toward the mean of its regions' rigid velocities:
  // mean_r (v_r + ω_r × (x − c_r)) = A + B × x,  A = mean (v_r − ω_r × c_r), B = mean ω_r
  tbb::parallel_for(tbb::blocked_range<int>(0, nseg, 64),
                    [&](const tbb::blocked_range<int>& range) {
                      for (int i = range.begin(); i < range.end(); ++i) {
                        const int n = share(i);
                        if (n == 0) continue;
                        Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
                        for (int j = m_seg_begin[i]; j < m_seg_begin[i + 1]; ++j) {
                          const RigidFit& f = m_fit[m_seg_regions[j]];
                          a += f.velocity - f.omega.cross(f.centre);
                          b += f.omega;
                        }
                        a /= n;
                        b /= n;
                        for (int k = 0; k < per; ++k) {
                          const int s = i * per + k;
                          dv.col(s) += alpha * (a + b.cross(x.col(s)) - u.col(s));
                        }
                      }
                    });
}

namespace {

RegionList without_unplaced(const Model& model, RegionList regions) {
  // segments without stitch coordinates are never touched
  for (auto& region : regions)
    region.erase(std::remove_if(region.begin(), region.end(),
                                [&](int i) {
                                  return i >= 0 && i < model.num_seg() && model.stitch[i].row < 0;
                                }),
                 region.end());
  return regions;
}

}  // namespace

NonRigidDampingFilter::NonRigidDampingFilter(const Model& model, double alpha_small,
                                             double alpha_large, bool wrap_columns,
                                             int samples_per_segment)
    : m_samples(model, samples_per_segment) {
  m_passes.emplace_back(model, without_unplaced(model, small_stitch_regions(model)), alpha_small);
  m_passes.emplace_back(
      model, without_unplaced(model, large_stitch_regions(model, 4, 2, wrap_columns)), alpha_large);
}

NonRigidDampingFilter::NonRigidDampingFilter(const Model& model, RegionList regions, double alpha,
                                             int samples_per_segment)
    : m_samples(model, samples_per_segment) {
  m_passes.emplace_back(model, std::move(regions), alpha);
}

void NonRigidDampingFilter::apply(const Model& model, const Eigen::VectorXd& q, Eigen::VectorXd& v,
                                  double /*time*/, double h) {
  // the sample buffers are kept between steps: no allocation (nor page faults) per step
  m_samples.positions(model, q, m_x);
  for (const RigidRegionPass& pass : m_passes) {
    if (pass.alpha() == 0 || pass.regions().empty()) continue;
    m_samples.positions(model, v, m_u);  // the velocities: the same basis applied to v
    m_dv.setZero(3, m_samples.num_samples());
    pass.velocity_change(m_samples, m_x, m_u, m_dv, per_step_strength(pass.alpha(), h));
    m_samples.apply(model, m_dv, v);
  }
}

}  // namespace knit
