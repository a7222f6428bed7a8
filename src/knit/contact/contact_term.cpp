#include "knit/contact/contact_term.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "knit/contact/contact_kernel.hpp"

namespace knit {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

bool has_damping(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  return v.size() == q.size() && (model.params.k_dt != 0 || model.params.k_dn != 0);
}

}  // namespace

ContactTerm::ContactTerm(const Model& model, ContactCulling culling) : m_culling(culling) {
  const int points = model.params.contact_points;
  if (points < 1 || points > MAX_CONTACT_POINTS)
    throw std::invalid_argument("params.contact_points: expected 1 to " +
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
  for (auto* a : {&m_px, &m_py, &m_pz, &m_vx, &m_vy, &m_vz}) a->assign(n, 0.0);
  m_boxes.assign(m_num_seg, Aabb{});
  m_partners.resize(m_num_seg);
  m_pairs.resize(m_num_seg);
  m_rows.assign(m_num_seg, RowStats{});
  m_row_records.resize(m_num_seg);
  m_bvh = Bvh{};
}

double ContactTerm::add_force(const Model& model, const Eigen::VectorXd& q,
                              const Eigen::VectorXd& v, Eigen::VectorXd& force) {
  assert(q.size() == model.num_dof() && force.size() == q.size());
  if (model.num_seg() != m_num_seg || model.contact_quad.size() != m_points) resize(model);
  m_stats = ContactStats{};
  m_timings = ContactTimings{};
  m_point_pairs.clear();
  const auto t0 = Clock::now();
  const double energy = m_culling == ContactCulling::BVH ? add_force_bvh(model, q, v, force)
                                                         : add_force_brute(model, q, v, force);
  m_timings.total = seconds_since(t0);
  return energy;
}

void ContactTerm::tabulate_points(const Model& model, const Eigen::VectorXd& q,
                                  const Eigen::VectorXd& v) {
  const QuadratureTable& quad = model.contact_quad;
  const double r = model.params.radius;
  const int P = m_points;
  const bool with_v = has_damping(model, q, v);
  tbb::parallel_for(tbb::blocked_range<int>(0, m_num_seg, 128),
                    [&](const tbb::blocked_range<int>& range) {
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
}

// The optimised pair kernel: the formulas of contact_kernel.cpp on the point pairs that
// survive culling. Points of i farther than r from box_j (= points of j grown by r) are
// farther than 2r from every point of j, and vice versa.
void ContactTerm::pair_kernel(const Model& model, int i, int j, RowStats& row) {
  const int P = m_points;
  const Params& prm = model.params;
  const QuadratureTable& quad = model.contact_quad;
  const double r = prm.radius;
  const double four_r2 = 4.0 * r * r;
  const double inv_four_r2 = 1.0 / four_r2;
  const size_t bi = static_cast<size_t>(i) * P, bj = static_cast<size_t>(j) * P;

  const Aabb near_j = m_boxes[j].grown(r);
  int ia[MAX_CONTACT_POINTS];
  int na = 0;
  for (int a = 0; a < P; ++a)
    if (near_j.contains(m_px[bi + a], m_py[bi + a], m_pz[bi + a])) ia[na++] = a;
  if (na == 0) return;
  const Aabb near_i = m_boxes[i].grown(r);
  int jb[MAX_CONTACT_POINTS];
  double bx[MAX_CONTACT_POINTS], by[MAX_CONTACT_POINTS], bz[MAX_CONTACT_POINTS];
  int nb = 0;
  for (int b = 0; b < P; ++b) {
    const double x = m_px[bj + b], y = m_py[bj + b], z = m_pz[bj + b];
    if (!near_i.contains(x, y, z)) continue;
    jb[nb] = b;
    bx[nb] = x;
    by[nb] = y;
    bz[nb] = z;
    ++nb;
  }
  if (nb == 0) return;
  row.tested += static_cast<long long>(na) * nb;

  const bool damp = m_has_velocity;
  const double li = model.rest_length[i], lj = model.rest_length[j];
  const double kl = prm.k_contact * li * lj;
  const double kdt = prm.k_dt, kdiff = prm.k_dt - prm.k_dn;
  // forces on the surviving points of i (fa*) and of j (fb*)
  double fax[MAX_CONTACT_POINTS], fay[MAX_CONTACT_POINTS], faz[MAX_CONTACT_POINTS];
  double fbx[MAX_CONTACT_POINTS], fby[MAX_CONTACT_POINTS], fbz[MAX_CONTACT_POINTS];
  std::fill_n(fbx, nb, 0.0);
  std::fill_n(fby, nb, 0.0);
  std::fill_n(fbz, nb, 0.0);
  int contacts = 0;
  double energy = 0;
  double min_d2 = row.min_d2;
  for (int ka = 0; ka < na; ++ka) {
    const int a = ia[ka];
    const double ax = m_px[bi + a], ay = m_py[bi + a], az = m_pz[bi + a];
    const double wa = quad.w[a];
    double sx = 0, sy = 0, sz = 0;
    for (int kb = 0; kb < nb; ++kb) {
      const double dx = bx[kb] - ax, dy = by[kb] - ay, dz = bz[kb] - az;
      const double d2 = dx * dx + dy * dy + dz * dz;
      if (!(d2 < four_r2)) continue;
      const int b = jb[kb];
      ++contacts;
      min_d2 = std::min(min_d2, d2);
      const double ww = wa * quad.w[b];
      // d = |Δy|/2r, f = 1/d² + d² − 2, f' = −2/d³ + 2d; the force on y_j(t_b),
      // −∂E/∂y_j = −k ℓℓ ww f'(d)/(2r) Δy/|Δy| = −k ℓℓ ww (2/4r²)(1 − 1/d⁴) Δy
      const double dd = d2 * inv_four_r2;
      const double inv_dd = four_r2 / d2;
      energy += kl * ww * (inv_dd + dd - 2.0);
      const double s = -kl * ww * 2.0 * inv_four_r2 * (1.0 - inv_dd * inv_dd);
      double fx = s * dx, fy = s * dy, fz = s * dz;
      if (damp) {
        const double inv = 1.0 / std::sqrt(d2);
        const double nx = dx * inv, ny = dy * inv, nz = dz * inv;
        const double dvx = m_vx[bj + b] - m_vx[bi + a];
        const double dvy = m_vy[bj + b] - m_vy[bi + a];
        const double dvz = m_vz[bj + b] - m_vz[bi + a];
        const double vn = nx * dvx + ny * dvy + nz * dvz;
        const double c = -2.0 * li * lj * ww;
        fx += c * (kdt * dvx - kdiff * vn * nx);
        fy += c * (kdt * dvy - kdiff * vn * ny);
        fz += c * (kdt * dvz - kdiff * vn * nz);
      }
      fbx[kb] += fx;
      fby[kb] += fy;
      fbz[kb] += fz;
      sx -= fx;
      sy -= fy;
      sz -= fz;
      if (m_record) m_row_records[i].push_back({i, a, j, b});
    }
    fax[ka] = sx;
    fay[ka] = sy;
    faz[ka] = sz;
  }
  row.min_d2 = min_d2;
  if (contacts == 0) return;
  row.contacts += contacts;
  row.energy += energy;
  PairForce& pf = m_pairs[i].emplace_back();
  pf.j = j;
  pf.force_i.setZero();
  pf.force_j.setZero();
  for (int ka = 0; ka < na; ++ka)
    scatter(pf.force_i, quad.b[ia[ka]], Eigen::Vector3d(fax[ka], fay[ka], faz[ka]));
  for (int kb = 0; kb < nb; ++kb)
    scatter(pf.force_j, quad.b[jb[kb]], Eigen::Vector3d(fbx[kb], fby[kb], fbz[kb]));
}

double ContactTerm::add_force_bvh(const Model& model, const Eigen::VectorXd& q,
                                  const Eigen::VectorXd& v, Eigen::VectorXd& force) {
  const int n = m_num_seg;
  m_has_velocity = has_damping(model, q, v);

  auto t = Clock::now();
  tabulate_points(model, q, v);
  m_timings.points = seconds_since(t);

  t = Clock::now();
  if (m_bvh.empty() || m_bvh.num_leaves() != n) {
    m_bvh.build(m_boxes);
    m_timings.build = seconds_since(t);
  } else {
    m_bvh.refit(m_boxes);
    m_timings.refit = seconds_since(t);
  }

  // candidate segment pairs: every segment queries the tree with its own box
  t = Clock::now();
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 64), [&](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i < range.end(); ++i) {
      std::vector<int>& partners = m_partners[i];
      partners.clear();
      m_rows[i] = RowStats{};
      m_rows[i].box_tests = m_bvh.query(m_boxes[i], [&](int j) {
        if (j != i && !model.neighbours(i, j)) partners.push_back(j);
      });
      std::sort(partners.begin(), partners.end());
    }
  });
  m_timings.traverse = seconds_since(t);

  // point-pair kernels, each pair (i < j) once, owned by row i
  t = Clock::now();
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 16), [&](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i < range.end(); ++i) {
      m_pairs[i].clear();
      if (m_record) m_row_records[i].clear();
      RowStats& row = m_rows[i];
      const std::vector<int>& partners = m_partners[i];
      for (auto it = std::upper_bound(partners.begin(), partners.end(), i); it != partners.end();
           ++it) {
        ++row.candidates;
        pair_kernel(model, i, *it, row);
      }
    }
  });
  m_timings.kernel = seconds_since(t);

  // per-segment sums in a fixed order: own pairs (i, j > i), then pairs (k < i, i)
  t = Clock::now();
  const double energy = m_accumulator.run(model, [&](int s, Vector12d& slot) {
    for (const PairForce& pf : m_pairs[s]) slot += pf.force_i;
    for (int k : m_partners[s]) {
      if (k >= s) break;
      const std::vector<PairForce>& row = m_pairs[k];
      const auto it = std::lower_bound(row.begin(), row.end(), s,
                                       [](const PairForce& pf, int j) { return pf.j < j; });
      if (it != row.end() && it->j == s) slot += it->force_j;
    }
    return m_rows[s].energy;
  });
  m_accumulator.gather(model, force, 1.0);
  m_timings.gather = seconds_since(t);

  double min_d2 = std::numeric_limits<double>::infinity();
  for (const RowStats& row : m_rows) {
    m_stats.candidate_segment_pairs += row.candidates;
    m_stats.point_pairs_tested += row.tested;
    m_stats.point_pairs_in_contact += row.contacts;
    m_stats.box_tests += row.box_tests;
    min_d2 = std::min(min_d2, row.min_d2);
  }
  if (std::isfinite(min_d2))
    m_stats.min_distance_ratio = std::sqrt(min_d2) / (2 * model.params.radius);
  if (m_record)
    for (const auto& rec : m_row_records)
      m_point_pairs.insert(m_point_pairs.end(), rec.begin(), rec.end());
  return energy;
}

double ContactTerm::add_force_brute(const Model& model, const Eigen::VectorXd& q,
                                    const Eigen::VectorXd& v, Eigen::VectorXd& force) {
  const QuadratureTable& quad = model.contact_quad;
  const bool damp = has_damping(model, q, v);
  Eigen::VectorXd no_velocity;
  if (!damp) no_velocity = Eigen::VectorXd::Zero(q.size());
  const Eigen::VectorXd& vel = damp ? v : no_velocity;
  const double two_r = 2 * model.params.radius;
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
