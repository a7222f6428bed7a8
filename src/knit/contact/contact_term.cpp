#include "knit/contact/contact_term.hpp"

// ContactTerm: construction, evaluation (dispatch), the contact points and the records;
// the pair traversal is in contact_pairs.cpp, the linearised reuse in contact_reuse.cpp.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "knit/contact/contact_kernel.hpp"
#include "knit/contact/contact_term_internal.hpp"
#include "knit/energy/lanes.hpp"

namespace knit {

using contact_detail::Clock;
using contact_detail::has_damping;
using contact_detail::seconds_since;

using lanes::LANES;

ContactTerm::ContactTerm(const Model& model, ContactCulling culling)
    : m_culling(culling), m_margin(DEFAULT_MARGIN_RADII * model.params.material.radius) {
  const int points = model.params.discretisation.contact_points;
  if (points < 1 || points > MAX_CONTACT_POINTS)
    throw std::invalid_argument("params.discretisation.contact_points: expected 1 to " +
                                std::to_string(MAX_CONTACT_POINTS) +
                                " contact points per segment, got " + std::to_string(points));
  resize(model);
}

void ContactTerm::resize(const Model& model) {
  m_num_seg = model.num_seg();
  m_points = model.contact_quad.size();
  if (m_points < 1 || m_points > MAX_CONTACT_POINTS)
    throw std::invalid_argument("contact quadrature: expected 1 to " +
                                std::to_string(MAX_CONTACT_POINTS) + " points per segment, got " +
                                std::to_string(m_points));
  const size_t n = static_cast<size_t>(m_num_seg) * m_points;
  // LANES spare entries at the end: the culling reads whole vectors of points
  for (auto* a : {&m_px, &m_py, &m_pz, &m_vx, &m_vy, &m_vz}) a->assign(n + LANES, 0.0);
  m_basis.resize(m_points);
  m_abscissae = model.contact_quad.t;
  for (int a = 0; a < m_points; ++a)
    for (int c = 0; c < 4; ++c) m_basis[a][c] = model.contact_quad.b[a][c];
  m_boxes.assign(m_num_seg, Aabb{});
  m_list_boxes.assign(m_num_seg, Aabb{});
  m_list_box_tests.assign(m_num_seg, 0);
  m_seg_moved.assign(m_num_seg, 0.0);
  m_list_valid = false;
  m_lin_valid = false;
  m_partners.resize(m_num_seg);
  m_pairs.resize(m_num_seg);
  m_row_kv.resize(m_num_seg);
  m_row_si.resize(m_num_seg);
  m_row_sj.resize(m_num_seg);
  m_rows.assign(m_num_seg, RowStats{});
  m_row_records.resize(m_num_seg);
  m_row_stiff.resize(m_num_seg);
  m_bvh = Bvh{};
}

void ContactTerm::set_candidate_margin(double margin) {
  if (!(margin >= 0) || !std::isfinite(margin))
    throw std::invalid_argument("contact candidate margin: expected a finite margin >= 0 cm, got " +
                                std::to_string(margin));
  m_margin = margin;
  m_margin_adaptive = false;
  m_list_valid = false;
}

double ContactTerm::add_force(const Model& model, const Eigen::VectorXd& q,
                              const Eigen::VectorXd& v, double time, Eigen::VectorXd& force) {
  assert(q.size() == model.num_dof() && force.size() == q.size());
  if (model.num_seg() != m_num_seg || model.contact_quad.size() != m_points) resize(model);
  const auto t0 = Clock::now();
  const double reuse =
      m_reuse_scale * model.params.solver.contact_reuse * model.params.material.radius;
  const bool reusing = reuse > 0 && m_stiffness && m_culling == ContactCulling::BVH;
  if (reusing && m_lin_valid && m_lin_model == &model && m_lin_q.size() == q.size()) {
    // within reach of the last exact evaluation? (the largest control point's move)
    m_lin_dq = q - m_lin_q;
    double moved2 = 0;
    for (Eigen::Index k = 0; k + 2 < m_lin_dq.size(); k += 3)
      moved2 = std::max(moved2, m_lin_dq.segment<3>(k).squaredNorm());
    if (moved2 <= reuse * reuse) {
      m_timings = ContactTimings{};
      const double energy = add_force_linearised(model, q, v, force);
      m_stats.linearised = true;
      ++m_linearised;
      m_timings.total = seconds_since(t0);
      return energy;
    }
  }
  m_stats = ContactStats{};
  m_timings = ContactTimings{};
  m_point_pairs.clear();
  ++m_evaluations;
  m_radius = model.params.material.radius;
  double energy = 0;
  if (reusing) {
    // kept as the linearisation's point: the state, the force and the energy
    m_lin_force.setZero(q.size());
    energy = add_force_bvh(model, q, v, m_lin_force);
    force += m_lin_force;
    m_lin_q = q;
    if (v.size() == q.size())
      m_lin_v = v;
    else
      m_lin_v.setZero(q.size());
    m_lin_energy = energy;
    m_lin_model = &model;
    m_lin_valid = true;
    // the kernels' K v₀, kept (add_force_linearised adds K (v − v₀) to it)
    m_lin_kv_valid = m_kv_valid && v.size() == q.size();
    if (m_lin_kv_valid) m_lin_kv0 = m_kv;
    m_block_state.assign(m_num_seg, 0);
    m_block_cache.resize(60 * static_cast<size_t>(m_num_seg));
  } else {
    m_lin_valid = false;
    energy = m_culling == ContactCulling::BVH ? add_force_bvh(model, q, v, force)
                                              : add_force_brute(model, q, v, force);
  }
  m_timings.total = seconds_since(t0);
  return energy;
}

void ContactTerm::tabulate_points(const Model& model, const Eigen::VectorXd& q,
                                  const Eigen::VectorXd& v) {
  const QuadratureTable& quad = model.contact_quad;
  const double r = model.params.material.radius;
  const int P = m_points;
  const bool with_v = has_damping(model, q, v);
  const bool check_motion = m_list_valid && m_culling == ContactCulling::BVH;
  tbb::parallel_for(
      tbb::blocked_range<int>(0, m_num_seg, 128), [&](const tbb::blocked_range<int>& range) {
        for (int s = range.begin(); s < range.end(); ++s) {
          const Vector12d x = gather_segment(q, model.seg_cp[s]);
          Aabb box;
          for (int a = 0; a < P; ++a) {
            const Eigen::Vector3d p = combine(x, quad.b[a]);
            const size_t k = static_cast<size_t>(s) * P + a;
            m_px[k] = p[0];
            m_py[k] = p[1];
            m_pz[k] = p[2];
            box.extend(p);
          }
          m_boxes[s] = box.grown(r);
          if (check_motion) {
            // largest per-axis displacement of the segment's points since the
            // candidate list was built
            // (+inf for a non-finite point: it forces a rebuild)
            double moved = 0;
            bool finite = true;
            for (int a = 0; a < P; ++a) {
              const size_t k = static_cast<size_t>(s) * P + a;
              moved = std::max({moved, std::abs(m_px[k] - m_lx[k]), std::abs(m_py[k] - m_ly[k]),
                                std::abs(m_pz[k] - m_lz[k])});
              finite = finite && std::isfinite(m_px[k] + m_py[k] + m_pz[k]);
            }
            m_seg_moved[s] = finite ? moved : std::numeric_limits<double>::infinity();
          }
          if (!with_v) continue;
          const Vector12d u = gather_segment(v, model.seg_cp[s]);
          for (int a = 0; a < P; ++a) {
            const Eigen::Vector3d w = combine(u, quad.b[a]);
            const size_t k = static_cast<size_t>(s) * P + a;
            m_vx[k] = w[0];
            m_vy[k] = w[1];
            m_vz[k] = w[2];
          }
        }
      });
  // the maximum is exact, so the order does not matter
  m_list_moved = 0;
  if (check_motion)
    for (int s = 0; s < m_num_seg; ++s) m_list_moved = std::max(m_list_moved, m_seg_moved[s]);
}

void ContactTerm::record(StepData& data) const {
  ContactRecord& c = data.contact;
  c.present = true;
  c.candidate_segment_pairs = m_stats.candidate_segment_pairs;
  c.point_pairs_tested = m_stats.point_pairs_tested;
  c.point_pairs_in_contact = m_stats.point_pairs_in_contact;
  c.min_distance_ratio = m_stats.min_distance_ratio;
  c.candidates_rebuilt = m_stats.candidates_rebuilt;
  c.linearised = m_stats.linearised;
  if (m_culling != ContactCulling::BVH) {
    c.pairs.clear();
    c.pairs_of = -1;
    return;
  }
  // a linearised state's pairs are those of the evaluation it reuses: the list stands
  if (c.pairs_of == m_evaluations) return;
  c.pairs_of = m_evaluations;
  c.pairs.clear();
  // row i's pairs go to [offset[i], offset[i + 1]): filled in parallel, in (i, j) order
  const int n = std::min<int>(m_num_seg, static_cast<int>(m_pairs.size()));
  m_record_offset.resize(n + 1);
  m_record_offset[0] = 0;
  for (int i = 0; i < n; ++i)
    m_record_offset[i + 1] = m_record_offset[i] + static_cast<long long>(m_pairs[i].size());
  c.pairs.resize(m_record_offset[n]);
  const double inv_two_r = 1.0 / (2 * m_radius);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 256), [&](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i < range.end(); ++i) {
      long long k = m_record_offset[i];
      for (const PairForce& pf : m_pairs[i]) {
        ContactPairRecord& r = c.pairs[k++];
        r.seg_i = i;
        r.seg_j = pf.j;
        const double len = pf.delta.norm();
        r.d = std::sqrt(pf.min_d2) * inv_two_r;
        r.normal = len > 0 ? Eigen::Vector3d(pf.delta / len) : Eigen::Vector3d::Zero();
        Eigen::Vector3d net = Eigen::Vector3d::Zero();
        for (int a = 0; a < 4; ++a) net += pf.force_j.segment<3>(3 * a);
        r.normal_force = r.normal.dot(net);
        r.t_i = m_abscissae[pf.point_a];
        r.t_j = m_abscissae[pf.point_b];
      }
    }
  });
}

double ContactTerm::add_force_brute(const Model& model, const Eigen::VectorXd& q,
                                    const Eigen::VectorXd& v, Eigen::VectorXd& force) {
  const QuadratureTable& quad = model.contact_quad;
  const bool damp = has_damping(model, q, v);
  Eigen::VectorXd no_velocity;
  if (!damp) no_velocity = Eigen::VectorXd::Zero(q.size());
  const Eigen::VectorXd& vel = damp ? v : no_velocity;
  const double two_r = 2 * model.params.material.radius;
  const int n = m_num_seg;
  double energy = 0;
  auto t = Clock::now();
  for (int i = 0; i < n; ++i) {
    const Vector12d xi = gather_segment(q, model.seg_cp[i]);
    const Vector12d vi = gather_segment(vel, model.seg_cp[i]);
    for (int j = i + 1; j < n; ++j) {
      if (model.neighbours(i, j)) continue;
      const Vector12d xj = gather_segment(q, model.seg_cp[j]);
      const Vector12d vj = gather_segment(vel, model.seg_cp[j]);
      const ContactPairResult res = contact_pair_force(xi, xj, vi, vj, model.rest_length[i],
                                                       model.rest_length[j], model.params, quad);
      ++m_stats.candidate_segment_pairs;
      m_stats.point_pairs_tested += static_cast<long long>(m_points) * m_points;
      if (res.min_distance_ratio < 1.0)
        m_stats.min_distance_ratio = std::min(m_stats.min_distance_ratio, res.min_distance_ratio);
      if (res.point_pairs_in_contact == 0) continue;
      m_stats.point_pairs_in_contact += res.point_pairs_in_contact;
      energy += res.energy;
      force.segment<12>(3 * model.seg_cp[i]) += res.force_i;
      force.segment<12>(3 * model.seg_cp[j]) += res.force_j;
      if (!m_record) continue;
      for (int a = 0; a < m_points; ++a)
        for (int b = 0; b < m_points; ++b) {
          const double d = (combine(xj, quad.b[b]) - combine(xi, quad.b[a])).norm() / two_r;
          if (d < 1.0) m_point_pairs.push_back({i, a, j, b});
        }
    }
  }
  m_timings.kernel = seconds_since(t);
  return energy;
}

}  // namespace knit
