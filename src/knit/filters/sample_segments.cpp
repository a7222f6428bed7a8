#include "knit/filters/sample_segments.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <stdexcept>
#include <string>

#include "knit/spline/basis.hpp"

namespace knit {

SampleSegments::SampleSegments(const Model& model, int samples_per_segment)
    : m_per(samples_per_segment) {
  if (m_per < 1)
    throw std::invalid_argument("samples_per_segment must be >= 1, got " + std::to_string(m_per));
  for (int k = 0; k < m_per; ++k) m_basis.push_back(bspline_basis((k + 0.5) / m_per));
  m_mass.assign(static_cast<size_t>(model.num_seg()) * m_per, 0.0);
  for (const YarnInfo& y : model.yarns) {
    double yarn_mass = 0, yarn_length = 0;
    for (int c = y.cp_begin; c < y.cp_end; ++c) yarn_mass += model.mass[c];
    for (int i = y.seg_begin; i < y.seg_end; ++i) yarn_length += model.rest_length[i];
    const double per_length = yarn_length > 0 ? yarn_mass / yarn_length : 0.0;
    for (int i = y.seg_begin; i < y.seg_end; ++i)
      for (int k = 0; k < m_per; ++k)
        m_mass[i * m_per + k] = model.rest_length[i] * per_length / m_per;
  }
}

Eigen::Matrix3Xd SampleSegments::positions(const Model& model, const Eigen::VectorXd& q) const {
  Eigen::Matrix3Xd x;
  positions(model, q, x);
  return x;
}

void SampleSegments::positions(const Model& model, const Eigen::VectorXd& q,
                               Eigen::Matrix3Xd& x) const {
  x.resize(3, num_samples());
  tbb::parallel_for(tbb::blocked_range<int>(0, model.num_seg(), 64),
                    [&](const tbb::blocked_range<int>& r) {
                      for (int i = r.begin(); i < r.end(); ++i) {
                        const Vector12d seg = gather_segment(q, model.seg_cp[i]);
                        for (int k = 0; k < m_per; ++k)
                          x.col(i * m_per + k) = combine(seg, m_basis[k]);
                      }
                    });
}

Eigen::Matrix3Xd SampleSegments::velocities(const Model& model, const Eigen::VectorXd& v) const {
  return positions(model, v);
}

void SampleSegments::apply(const Model& model, const Eigen::Matrix3Xd& dv,
                           Eigen::VectorXd& v) const {
  const int nseg = model.num_seg();
  // per segment: the impulse on each of its 4 control points
  std::vector<Vector12d>& slot = m_slot;
  slot.resize(nseg);
  tbb::parallel_for(tbb::blocked_range<int>(0, nseg, 64), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i < r.end(); ++i) {
      slot[i].setZero();
      for (int k = 0; k < m_per; ++k) {
        const int s = i * m_per + k;
        scatter(slot[i], m_basis[k], m_mass[s] * dv.col(s));
      }
    }
  });
  // per control point: the ≤ 4 segments touching it, in increasing segment order
  for (const YarnInfo& y : model.yarns) {
    tbb::parallel_for(tbb::blocked_range<int>(y.cp_begin, y.cp_end, 256),
                      [&](const tbb::blocked_range<int>& r) {
                        for (int c = r.begin(); c < r.end(); ++c) {
                          Eigen::Vector3d j = Eigen::Vector3d::Zero();
                          const int local = c - y.cp_begin;
                          for (int a = 3; a >= 0; --a) {
                            const int i = y.seg_begin + local - a;
                            if (i < y.seg_begin || i >= y.seg_end) continue;
                            j += slot[i].segment<3>(3 * a);
                          }
                          v.segment<3>(3 * c) += j / model.mass[c];
                        }
                      });
  }
}

void SampleSegments::apply_segments(const Model& model, const std::vector<int>& segments,
                                    const Eigen::Matrix3Xd& dv, Eigen::VectorXd& v) const {
  for (int i : segments) {
    Vector12d slot = Vector12d::Zero();
    for (int k = 0; k < m_per; ++k) {
      const int s = i * m_per + k;
      scatter(slot, m_basis[k], m_mass[s] * dv.col(s));
    }
    const int c0 = model.seg_cp[i];
    for (int a = 0; a < 4; ++a)
      v.segment<3>(3 * (c0 + a)) += slot.segment<3>(3 * a) / model.mass[c0 + a];
  }
}

}  // namespace knit
