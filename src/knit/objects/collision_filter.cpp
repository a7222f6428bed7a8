#include "knit/objects/collision_filter.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "knit/objects/object.hpp"

namespace knit {

CollisionFilter::CollisionFilter(const Model& model, int samples_per_segment)
    : m_samples(model, samples_per_segment) {
  for (size_t k = 0; k < model.objects.size(); ++k)
    if (model.objects[k]->filter) m_objects.push_back(static_cast<int>(k));
  m_last.resize(m_objects.size());
}

void CollisionFilter::apply(const Model& model, const Eigen::VectorXd& q, Eigen::VectorXd& v,
                            double time, double h) {
  m_h = h;
  m_changed = false;
  std::fill(m_last.begin(), m_last.end(), ObjectContacts{});
  if (m_objects.empty()) return;
  const double r = model.params.material.radius;
  const int per = m_samples.samples_per_segment();
  const int nobj = static_cast<int>(m_objects.size());
  std::vector<ObjectFrame> frames;
  for (int k : m_objects) frames.emplace_back(*model.objects[k], time);

  // segments whose ball comes within r of some object
  const int nseg = model.num_seg();
  std::vector<char>& near = m_is_near;
  near.assign(nseg, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, nseg, 256), [&](const tbb::blocked_range<int>& b) {
    for (int i = b.begin(); i < b.end(); ++i) {
      Eigen::Vector3d centre;
      double rho;
      segment_ball(model, q, i, centre, rho);
      for (const ObjectFrame& f : frames)
        if (!f.ball_outside(centre, rho, r)) {
          near[i] = 1;
          break;
        }
    }
  });
  m_near.clear();
  for (int i = 0; i < nseg; ++i)
    if (near[i]) m_near.push_back(i);
  if (m_near.empty()) return;

  // the hits at the step's positions (fixed over the passes), in blocks of BLOCK near
  // segments: each block's hits are written and read by one task, in segment order
  constexpr size_t BLOCK = 64;
  const size_t nblocks = (m_near.size() + BLOCK - 1) / BLOCK;
  if (m_blocks.size() < nblocks) m_blocks.resize(nblocks);
  const double max_push = 0.25 * r;
  tbb::parallel_for(size_t(0), nblocks, [&](size_t blk) {
    std::vector<Hit>& out = m_blocks[blk];
    out.clear();
    for (size_t j = blk * BLOCK; j < std::min(m_near.size(), (blk + 1) * BLOCK); ++j) {
      const int i = m_near[j];
      const Vector12d x = gather_segment(q, model.seg_cp[i]);
      for (int k = 0; k < per; ++k) {
        const Eigen::Vector3d xs = combine(x, m_samples.basis(k));
        for (int o = 0; o < nobj; ++o) {
          Eigen::Vector3d g;
          const double phi = frames[o].distance(xs, &g);
          const double gn = g.norm();
          if (!(phi < r) || !(gn > 0)) continue;
          Hit hit;
          hit.sample = i * per + k;
          hit.object = o;
          hit.near = static_cast<int>(j);
          hit.x = xs;
          hit.n = g / gn;
          hit.depth = r - phi;
          hit.push = std::min(r - phi, max_push) / h;
          out.push_back(hit);
        }
      }
    }
  });
  for (size_t blk = 0; blk < nblocks; ++blk)
    for (const Hit& hit : m_blocks[blk]) {
      ObjectContacts& st = m_last[hit.object];
      ++st.points;
      st.deepest = std::max(st.deepest, hit.depth);
    }

  if (m_dv.cols() != m_samples.num_samples()) {
    m_dv = Eigen::Matrix3Xd::Zero(3, m_samples.num_samples());
    m_dvt = m_dv;
  }
  std::vector<Eigen::Vector3d> impulse(nblocks * nobj);
  std::vector<char> changed(m_near.size());
  for (int pass = 0; pass < PASSES; ++pass) {
    std::fill(impulse.begin(), impulse.end(), Eigen::Vector3d::Zero());
    std::fill(changed.begin(), changed.end(), 0);
    tbb::parallel_for(size_t(0), nblocks, [&](size_t blk) {
      int last_near = -1;
      Vector12d u;
      for (const Hit& hit : m_blocks[blk]) {
        const int i = m_near[hit.near];
        if (hit.near != last_near) {
          u = gather_segment(v, model.seg_cp[i]);
          last_near = hit.near;
        }
        const int k = hit.sample - i * per;
        const Eigen::Vector3d w =
            combine(u, m_samples.basis(k)) - frames[hit.object].velocity(hit.x);
        const double wn = w.dot(hit.n);
        const double dwn = hit.push - wn;
        if (!(dwn > 1e-9)) continue;
        const Eigen::Vector3d wt = w - wn * hit.n;
        const double nt = wt.norm();
        const double mu = model.objects[m_objects[hit.object]]->friction;
        Eigen::Vector3d dv = dwn * hit.n;
        if (nt > 0) {
          const Eigen::Vector3d dvt = -std::min(1.0, mu * dwn / nt) * wt;
          dv += dvt;
          m_dvt.col(hit.sample) += dvt;
        }
        m_dv.col(hit.sample) += dv;
        impulse[blk * nobj + hit.object] += m_samples.mass(hit.sample) * dv;
        changed[hit.near] = 1;
      }
    });
    for (size_t b = 0; b < nblocks; ++b)
      for (int o = 0; o < nobj; ++o) m_last[o].push += impulse[b * nobj + o];
    m_changed_segments.clear();
    for (size_t j = 0; j < m_near.size(); ++j)
      if (changed[j]) m_changed_segments.push_back(m_near[j]);
    if (m_changed_segments.empty()) break;
    if (!m_changed) m_touched = m_changed_segments;  // later passes touch a subset
    m_changed = true;
    m_samples.apply_segments(model, m_changed_segments, m_dv, v);
    for (int i : m_changed_segments) m_dv.middleCols(i * per, per).setZero();
  }
  if (m_changed) {
    // the friction part of the change, on the control points
    m_dvt_cp.setZero(v.size());
    m_samples.apply_segments(model, m_touched, m_dvt, m_dvt_cp);
    for (int i : m_touched) m_dvt.middleCols(i * per, per).setZero();
  }
}

bool CollisionFilter::adjust_positions(const Model& model, Eigen::VectorXd& q) const {
  if (!m_changed) return false;
  q += (0.5 * m_h) * m_dvt_cp;
  return true;
}

void CollisionFilter::record(StepData& data) const {
  record_contacts(m_objects, m_last, m_h > 0 ? 1.0 / m_h : 0.0, data);
}

}  // namespace knit
