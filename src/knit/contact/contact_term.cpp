#include "knit/contact/contact_term.hpp"

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
#include "knit/energy/lanes.hpp"

namespace knit {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

using lanes::any;
using lanes::lane_bits;
using lanes::lane_sum;
using lanes::LANES;
using lanes::load;
using lanes::splat;
using lanes::store;
using lanes::VecD;
using lanes::VecL;

// a vector of point pairs' (x, y, z): added at j's points (bx, by, bz), taken from i's
// point's lane sums (sx, sy, sz)
inline void add_pair(VecD x, VecD y, VecD z, double* bx, double* by, double* bz, VecD& sx, VecD& sy,
                     VecD& sz) {
  store(bx, load(bx) + x);
  store(by, load(by) + y);
  store(bz, load(bz) + z);
  sx -= x;
  sy -= y;
  sz -= z;
}

// out = (x₀, y₀, z₀, …, x₃, y₃, z₃): a segment's 4 control points, one per lane, per axis
void interleave(VecD x, VecD y, VecD z, Vector12d& out) {
  for (int c = 0; c < 4; ++c) {
    out[3 * c] = x[c];
    out[3 * c + 1] = y[c];
    out[3 * c + 2] = z[c];
  }
}

bool has_damping(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  return v.size() == q.size() &&
         (model.params.material.k_dt != 0 || model.params.material.k_dn != 0);
}

}  // namespace

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

double ContactTerm::add_force_linearised(const Model& model, const Eigen::VectorXd& q,
                                         const Eigen::VectorXd& v, Eigen::VectorXd& force) {
  // m_lin_dq = q − q₀ (add_force); the velocity's change, a missing v read as rest
  const bool damp = model.params.material.k_dt != 0 || model.params.material.k_dn != 0;
  if (damp) {
    if (v.size() == q.size())
      m_lin_dv = v - m_lin_v;
    else
      m_lin_dv = -m_lin_v;
  }
  const int rows = std::min<int>(m_num_seg, static_cast<int>(m_stiff_offset.size()) - 1);
  if (rows <= 0) {
    force += m_lin_force;
    return m_lin_energy;
  }
  flatten(model);
  const double kdt = model.params.material.k_dt;
  const double kdiff = model.params.material.k_dt - model.params.material.k_dn;
  // the stiffness product K v for the step's right-hand side, formed on the way: K v₀ came
  // from the exact evaluation's kernels, and K (v − v₀) takes w from the damping's pass
  const bool fuse_kv = damp && v.size() == q.size() && m_lin_kv_valid;
  m_lin_pair_force.resize(m_stiff_offset[rows]);
  m_lin_row_energy.assign(m_num_seg, 0.0);
  // per point pair: u and w the changes of Δ and of Δv, the force change on j
  //   −H u = −(kn + 2 kt/|Δ|²)(Δ·u) Δ + kt u   (H = k n̂n̂ᵀ − kt (I − n̂n̂ᵀ), the exact
  //   Hessian: the kernels' kn, kt are the mirrored one's, kn ΔΔᵀ + kt I)
  // plus damping's −2 ℓℓ ww [k_dt w − (k_dt − k_dn)(Δ·w) Δ/|Δ|²], and the energy change
  // −F_j⁰·u + ½ uᵀH u with F_j⁰ = kt Δ (the kernels' force on j is g Δ, g = kt)
  tbb::parallel_for(tbb::blocked_range<int>(0, rows, 16), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i < r.end(); ++i) {
      double energy = 0;
      for (int k = m_stiff_offset[i]; k < m_stiff_offset[i + 1]; ++k) {
        const FlatPair& p = m_flat[k];
        const int ci = p.ci, cj = p.cj;
        const std::array<double, 4>& ba = m_basis[p.a];
        const std::array<double, 4>& bb = m_basis[p.b];
        Eigen::Vector3d u = Eigen::Vector3d::Zero();
        for (int c = 0; c < 4; ++c)
          u +=
              bb[c] * m_lin_dq.segment<3>(3 * (cj + c)) - ba[c] * m_lin_dq.segment<3>(3 * (ci + c));
        const Eigen::Vector3d delta(p.dx, p.dy, p.dz);
        const double len2 = delta.squaredNorm();
        const double kn_exact = p.kn + 2 * p.kt / len2;
        const double du = delta.dot(u);
        Eigen::Matrix<double, 3, 2>& out = m_lin_pair_force[k];
        auto f = out.col(0);
        f = p.kt * u - (kn_exact * du) * delta;
        out.col(1).setZero();
        energy += -p.kt * du + 0.5 * (kn_exact * du * du - p.kt * u.squaredNorm());
        if (damp) {
          Eigen::Vector3d w = Eigen::Vector3d::Zero();
          for (int c = 0; c < 4; ++c)
            w += bb[c] * m_lin_dv.segment<3>(3 * (cj + c)) -
                 ba[c] * m_lin_dv.segment<3>(3 * (ci + c));
          const double dw = delta.dot(w);
          f += p.c2 * (kdt * w - (kdiff * dw / len2) * delta);
          if (fuse_kv) out.col(1) = (p.kn * dw) * delta + p.kt * w;
        }
      }
      m_lin_row_energy[i] = energy;
    }
  });
  // per segment in the fixed order of segment_product (force and K v in one pass)
  m_product_accumulator.run2(
      model, m_kv_accumulator, [&](int s, Vector12d& slot, Vector12d& kv_slot) {
        if (s >= rows) return 0.0;
        Eigen::Matrix<double, 12, 2> both = Eigen::Matrix<double, 12, 2>::Zero();
        segment_product(
            s, [&](int k) -> const Eigen::Matrix<double, 3, 2>& { return m_lin_pair_force[k]; },
            both);
        slot = both.col(0);
        kv_slot = both.col(1);
        return 0.0;
      });
  force += m_lin_force;
  m_product_accumulator.gather(model, force, 1.0);
  if (fuse_kv) {
    m_kv = m_lin_kv0;
    m_kv_accumulator.gather(model, m_kv, 1.0);
    m_kv_velocity = v;
    m_kv_valid = true;
  }
  double energy = m_lin_energy;
  for (double e : m_lin_row_energy) energy += e;
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

// The optimised pair kernel: the formulas of contact_kernel.cpp on the point pairs that
// survive culling. Points of i farther than r from box_j (= points of j grown by r) are
// farther than 2r from every point of j, and vice versa.
//
// The surviving points of j are copied into short aligned arrays padded to a multiple of
// LANES with far-away points, and every point of i is tested against them LANES at a time
// with GCC/Clang vector extensions, branch-free: the force of a lane out of contact is
// blended to 0. There is no square root: with Δy the separation and d² = |Δy|²/4r²,
//   contact:  F_j = −k ℓℓ ww (2/4r²)(1 − 1/d⁴) Δy
//   damping:  F_j = −2 ℓℓ ww [k_dt Δv − (k_dt − k_dn)(Δy·Δv) Δy / |Δy|²]
// ((n̂·Δv) n̂ = (Δy·Δv) Δy/|Δy|²), so one division 1/|Δy|² per tested pair serves both.
// Sums over lanes are formed lane-wise and reduced in a fixed order: the result is a pure
// function of the inputs (round-off differs from the plain kernel's order only).
//
// With STIFF (the stiffness operator on) the kernel also forms, per point pair in contact,
// its stiffness k n̂n̂ᵀ + kt (I − n̂n̂ᵀ) = kn ΔyΔyᵀ + kt I with
//   kn = (k − kt)/|Δy|² = c (4/d⁴ + 4)/(4r² |Δy|²),  kt = c (2/d⁴ − 2)/4r²
// (k = c f''(d)/4r², kt = c |f'(d)|/(2r |Δy|), c = k ℓℓ ww; again no square root), and sums
// its six numbers per contact point: over the row's pairs at i's points (`own`), per pair at
// j's points (m_row_sj). With damping's velocities at hand too it forms the operator's
// product with the velocity, K v: per point pair f = kn (Δy·Δv) Δy + kt Δv
// (pair_product's formula with u = Δv), B_b f on j's control points and −B_a f on i's.
template <bool DAMP, bool STIFF>
void ContactTerm::pair_kernel(const Model& model, int i, int j, RowStats& row, OwnStiffness& own) {
  constexpr bool KV = DAMP && STIFF;
  // a candidate kept from an older list whose current boxes no longer overlap has no
  // point pair within 2r (see add_force_bvh) and is not counted
  if (!m_boxes[i].overlaps(m_boxes[j])) return;
  ++row.candidates;
  const int stiff_begin = STIFF ? static_cast<int>(m_row_stiff[i].size()) : 0;
  const int P = m_points;
  const Params& prm = model.params;
  const QuadratureTable& quad = model.contact_quad;
  const double r = prm.material.radius;
  const double four_r2 = 4.0 * r * r;
  const double inv_four_r2 = 1.0 / four_r2;
  const size_t bi = static_cast<size_t>(i) * P, bj = static_cast<size_t>(j) * P;

  int ia[MAX_CONTACT_POINTS + LANES];
  const int na = points_inside(m_boxes[j].grown(r), bi, ia);
  if (na == 0) return;
  constexpr int CAP = MAX_CONTACT_POINTS + LANES;
  int jb[CAP];
  const int nb = points_inside(m_boxes[i].grown(r), bj, jb);
  if (nb == 0) return;
  alignas(64) double bx[CAP], by[CAP], bz[CAP], bw[CAP];
  alignas(64) double bvx[DAMP ? CAP : 1], bvy[DAMP ? CAP : 1], bvz[DAMP ? CAP : 1];
  for (int kb = 0; kb < nb; ++kb) {
    const size_t k = bj + jb[kb];
    bx[kb] = m_px[k];
    by[kb] = m_py[k];
    bz[kb] = m_pz[k];
    bw[kb] = quad.w[jb[kb]];
    if constexpr (DAMP) {
      bvx[kb] = m_vx[k];
      bvy[kb] = m_vy[k];
      bvz[kb] = m_vz[k];
    }
  }
  row.tested += static_cast<long long>(na) * nb;
  // pad with points 1e10 cm away: their lanes are never in contact and stay finite
  const int nbp = (nb + LANES - 1) / LANES * LANES;
  for (int k = nb; k < nbp; ++k) {
    bx[k] = by[k] = bz[k] = 1e10;
    bw[k] = 0.0;
    if constexpr (DAMP) bvx[k] = bvy[k] = bvz[k] = 0.0;
  }

  const double li = model.rest_length[i], lj = model.rest_length[j];
  const double kl = prm.material.k_contact * li * lj;
  const double kdt = prm.material.k_dt, kdiff = prm.material.k_dt - prm.material.k_dn;
  // forces on the surviving points of j (fb*); those on the points of i go straight into
  // gi* = Σ_a B(t_a) f_a per axis (the 4 control points of segment i in the lanes)
  static_assert(LANES == 4, "the basis scatter keeps the 4 control points in one vector");
  VecD gix = splat(0.0), giy = gix, giz = gix;
  alignas(64) double fbx[CAP], fby[CAP], fbz[CAP];
  alignas(64) double d2row[CAP];
  std::fill_n(fbx, nbp, 0.0);
  std::fill_n(fby, nbp, 0.0);
  std::fill_n(fbz, nbp, 0.0);
  alignas(64) double kbx[KV ? CAP : 1], kby[KV ? CAP : 1], kbz[KV ? CAP : 1];
  // per point of j: the sums of the six numbers (STIFF), and per lane of the current row of
  // point pairs kn and kt
  alignas(64) double sb[STIFF ? 6 : 1][STIFF ? CAP : 1];
  alignas(64) double knrow[STIFF ? CAP : 1], ktrow[STIFF ? CAP : 1];
  if constexpr (STIFF)
    for (auto& e : sb) std::fill_n(e, nbp, 0.0);
  VecD kix = splat(0.0), kiy = kix, kiz = kix;
  if constexpr (KV) {
    std::fill_n(kbx, nbp, 0.0);
    std::fill_n(kby, nbp, 0.0);
    std::fill_n(kbz, nbp, 0.0);
  }
  const VecD four_r2_v = splat(four_r2), inv_four_r2_v = splat(inv_four_r2);
  const VecD zero = splat(0.0), one = splat(1.0), two = splat(2.0);
  VecD energy = zero, min_d2 = splat(std::numeric_limits<double>::infinity());
  VecD mdx = zero, mdy = zero, mdz = zero;  // Δy of the closest point pair, lane-wise
  VecD mda = zero, mdb = zero;              // and its points (a, and b's index kb + lane)
  const VecD lane_index = {0.0, 1.0, 2.0, 3.0};
  VecL contacts = VecL{};
  for (int ka = 0; ka < na; ++ka) {
    const int a = ia[ka];
    const VecD ax = splat(m_px[bi + a]), ay = splat(m_py[bi + a]), az = splat(m_pz[bi + a]);
    const VecD kla = splat(kl * quad.w[a]);
    VecD avx = zero, avy = zero, avz = zero, lla = zero;
    if constexpr (DAMP) {
      avx = splat(m_vx[bi + a]);
      avy = splat(m_vy[bi + a]);
      avz = splat(m_vz[bi + a]);
      lla = splat(-2.0 * li * lj * quad.w[a]);
    }
    VecD sx = zero, sy = zero, sz = zero;
    VecD ksx = zero, ksy = zero, ksz = zero;
    VecD sa[STIFF ? 6 : 1];
    for (VecD& e : sa) e = zero;
    VecL a_contacts = VecL{};
    for (int kb = 0; kb < nbp; kb += LANES) {
      const VecD dx = load(bx + kb) - ax, dy = load(by + kb) - ay, dz = load(bz + kb) - az;
      const VecD d2 = dx * dx + dy * dy + dz * dz;
      store(d2row + kb, d2);
      const VecL in = d2 < four_r2_v;
      // most vectors have no lane in contact (the boxes are loose): skip the rest
      if (!any(in)) continue;
      const VecD inv_d2 = one / d2;
      const VecD inv_dd = four_r2_v * inv_d2;  // 1/d²
      const VecD w = load(bw + kb);
      const VecD kw = kla * w;  // k ℓℓ ww
      // f(d) = 1/d² + d² − 2; the force on y_j(t_b) is g Δy (+ damping)
      energy += in ? kw * (inv_dd + d2 * inv_four_r2_v - two) : zero;
      VecD g = -two * inv_four_r2_v * kw * (one - inv_dd * inv_dd);
      VecD kn = zero, kt = zero;
      if constexpr (STIFF) {
        const VecD i4 = inv_dd * inv_dd, kc = kw * inv_four_r2_v;
        kn = in ? kc * (splat(4.0) * i4 + splat(4.0)) * inv_d2 : zero;
        kt = in ? kc * (two * i4 - two) : zero;
        store(knrow + kb, kn);
        store(ktrow + kb, kt);
        const VecD nx = kn * dx, ny = kn * dy, nz = kn * dz;
        const VecD e[6] = {nx * dx + kt, nx * dy, nx * dz, ny * dy + kt, ny * dz, nz * dz + kt};
        for (int c = 0; c < 6; ++c) {
          sa[c] += e[c];
          store(sb[c] + kb, load(sb[c] + kb) + e[c]);
        }
        a_contacts |= in;
      }
      VecD fx, fy, fz;
      if constexpr (DAMP) {
        const VecD dvx = load(bvx + kb) - avx, dvy = load(bvy + kb) - avy,
                   dvz = load(bvz + kb) - avz;
        const VecD c = lla * w;                           // −2 ℓℓ ww
        const VecD dot = dx * dvx + dy * dvy + dz * dvz;  // Δy·Δv
        g -= c * splat(kdiff) * dot * inv_d2;
        const VecD ct = c * splat(kdt);
        fx = g * dx + ct * dvx;
        fy = g * dy + ct * dvy;
        fz = g * dz + ct * dvz;
        if constexpr (KV) {
          const VecD knd = kn * dot;
          const VecD kx = knd * dx + kt * dvx, ky = knd * dy + kt * dvy, kz = knd * dz + kt * dvz;
          add_pair(kx, ky, kz, kbx + kb, kby + kb, kbz + kb, ksx, ksy, ksz);
        }
      } else {
        fx = g * dx;
        fy = g * dy;
        fz = g * dz;
      }
      fx = in ? fx : zero;
      fy = in ? fy : zero;
      fz = in ? fz : zero;
      contacts -= in;  // a true comparison is −1
      const VecL closer = d2 < min_d2;
      mdx = closer ? dx : mdx;
      mdy = closer ? dy : mdy;
      mdz = closer ? dz : mdz;
      mda = closer ? splat(a) : mda;
      mdb = closer ? splat(kb) + lane_index : mdb;
      min_d2 = closer ? d2 : min_d2;
      add_pair(fx, fy, fz, fbx + kb, fby + kb, fbz + kb, sx, sy, sz);
    }
    const VecD basis_a = load(m_basis[a].data());
    gix += basis_a * lane_sum(sx);
    giy += basis_a * lane_sum(sy);
    giz += basis_a * lane_sum(sz);
    if constexpr (KV) {
      kix += basis_a * lane_sum(ksx);
      kiy += basis_a * lane_sum(ksy);
      kiz += basis_a * lane_sum(ksz);
    }
    if (m_record)
      for (int kb = 0; kb < nb; ++kb)
        if (d2row[kb] < four_r2) m_row_records[i].push_back({i, a, j, jb[kb]});
    if constexpr (STIFF) {
      if (!any(a_contacts)) continue;
      std::array<double, 6>& sum = own.s[a];
      if (!own.used[a]) {
        sum.fill(0.0);
        own.used[a] = 1;
      }
      for (int c = 0; c < 6; ++c) sum[c] += lane_sum(sa[c]);
      for (int kb = 0; kb < nb; ++kb) {
        if (!(d2row[kb] < four_r2)) continue;
        m_row_stiff[i].push_back({j, a, jb[kb], bx[kb] - m_px[bi + a], by[kb] - m_py[bi + a],
                                  bz[kb] - m_pz[bi + a], knrow[kb], ktrow[kb]});
      }
    }
  }
  // the smallest squared distance over all lanes is < 4r² exactly when some pair is in
  // contact, and then it is the smallest over the pairs in contact
  const double lane_min = lanes::lane_min(min_d2);
  if (lane_min < four_r2) row.min_d2 = std::min(row.min_d2, lane_min);
  long long n_contacts = 0;
  for (int l = 0; l < LANES; ++l) n_contacts += contacts[l];
  if (n_contacts == 0) return;
  row.contacts += n_contacts;
  row.energy += lane_sum(energy);
  VecD gjx = splat(0.0), gjy = gjx, gjz = gjx;
  VecD kjx = gjx, kjy = gjx, kjz = gjx;
  for (int kb = 0; kb < nb; ++kb) {
    const VecD basis_b = load(m_basis[jb[kb]].data());
    gjx += basis_b * fbx[kb];
    gjy += basis_b * fby[kb];
    gjz += basis_b * fbz[kb];
    if constexpr (KV) {
      kjx += basis_b * kbx[kb];
      kjy += basis_b * kby[kb];
      kjz += basis_b * kbz[kb];
    }
  }
  PairForce& pf = m_pairs[i].emplace_back();
  pf.j = j;
  pf.min_d2 = lane_min;
  if constexpr (STIFF) {
    pf.stiff_begin = stiff_begin;
    pf.stiff_end = static_cast<int>(m_row_stiff[i].size());
    // j's points in contact and their sums
    std::vector<PointStiffness>& sj = m_row_sj[i];
    pf.sj_begin = static_cast<int>(sj.size());
    for (int kb = 0; kb < nb; ++kb) {
      // a point of j in contact has a positive sum on the diagonal (kt ≥ 0, kn > 0)
      if (!(sb[0][kb] + sb[3][kb] + sb[5][kb] > 0)) continue;
      PointStiffness& ps = sj.emplace_back();
      ps.point = jb[kb];
      for (int c = 0; c < 6; ++c) ps.s[c] = sb[c][kb];
    }
    pf.sj_end = static_cast<int>(sj.size());
  }
  for (int l = 0; l < LANES; ++l)
    if (min_d2[l] == lane_min) {
      pf.delta = Eigen::Vector3d(mdx[l], mdy[l], mdz[l]);
      pf.point_a = static_cast<int>(mda[l]);
      pf.point_b = jb[static_cast<int>(mdb[l])];
      break;
    }
  interleave(gix, giy, giz, pf.force_i);
  interleave(gjx, gjy, gjz, pf.force_j);
  if constexpr (KV) {
    PairKv& kv = m_row_kv[i].emplace_back();
    interleave(kix, kiy, kiz, kv.i);
    interleave(kjx, kjy, kjz, kv.j);
  }
}

// Indices of the points of segment (first point `base`) inside `box`, in order; returns
// their count. Whole vectors of points are tested at once; the lanes past the segment's
// last point are dropped.
int ContactTerm::points_inside(const Aabb& box, size_t base, int* out) const {
  const VecD lx = splat(box.lo[0]), ly = splat(box.lo[1]), lz = splat(box.lo[2]);
  const VecD hx = splat(box.hi[0]), hy = splat(box.hi[1]), hz = splat(box.hi[2]);
  int n = 0;
  for (int a0 = 0; a0 < m_points; a0 += LANES) {
    const VecD x = load(&m_px[base + a0]), y = load(&m_py[base + a0]), z = load(&m_pz[base + a0]);
    unsigned bits =
        lane_bits((x >= lx) & (x <= hx) & (y >= ly) & (y <= hy) & (z >= lz) & (z <= hz));
    if (m_points - a0 < LANES) bits &= (1u << (m_points - a0)) - 1;
    for (; bits; bits &= bits - 1) out[n++] = a0 + std::countr_zero(bits);
  }
  return n;
}

double ContactTerm::add_force_bvh(const Model& model, const Eigen::VectorXd& q,
                                  const Eigen::VectorXd& v, Eigen::VectorXd& force) {
  const int n = m_num_seg;
  m_has_velocity = has_damping(model, q, v);

  auto t = Clock::now();
  tabulate_points(model, q, v);
  m_timings.points = seconds_since(t);

  // candidate segment pairs, rebuilt only when some point moved more than δ/2 (see the
  // header: the reused list gives the same forces bitwise)
  const double r = model.params.material.radius;
  const bool moved_out = m_list_valid && !(m_list_moved <= 0.5 * m_list_margin);
  const bool same_model = m_list_valid && m_list_model == &model && m_list_radius == r;
  // the list's lifetime in evaluations, this one included
  const long long lasted = m_evaluations - m_list_built_at;
  // a grown margin that has outlived its need is shrunk at a rebuild of its own (the list
  // is kept while nothing moves, and a wider list costs the kernels a box test per
  // candidate)
  const bool shrink = same_model && m_margin_adaptive && lasted > MAX_LIST_EVALUATIONS &&
                      m_list_margin > DEFAULT_MARGIN_RADII * r;
  const bool rebuild = !same_model || moved_out || shrink;
  m_stats.candidates_rebuilt = rebuild;
  m_rebuilds += rebuild;
  if (same_model && m_margin_adaptive && (moved_out || shrink)) {
    if (lasted < MIN_LIST_EVALUATIONS)
      m_margin = std::min(1.5 * m_margin, MAX_ADAPTIVE_MARGIN_RADII * r);
    else if (lasted > MAX_LIST_EVALUATIONS)
      m_margin = std::max(m_margin / 1.5, DEFAULT_MARGIN_RADII * r);
  }
  const double half_margin = 0.5 * m_margin;
  if (rebuild) {
    m_list_margin = m_margin;
    m_list_built_at = m_evaluations;
    t = Clock::now();
    m_lx = m_px;
    m_ly = m_py;
    m_lz = m_pz;
    for (int s = 0; s < n; ++s) m_list_boxes[s] = m_boxes[s].grown(half_margin);
    if (m_bvh.empty() || m_bvh.num_leaves() != n) {
      m_bvh.build(m_list_boxes);
      m_timings.build = seconds_since(t);
    } else {
      m_bvh.refit(m_list_boxes);
      m_timings.refit = seconds_since(t);
    }
    // every segment queries the tree with its own (grown) box
    t = Clock::now();
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 64), [&](const tbb::blocked_range<int>& range) {
      for (int i = range.begin(); i < range.end(); ++i) {
        std::vector<int>& partners = m_partners[i];
        partners.clear();
        // the partners after i alone: row i owns the pairs (i, j > i)
        m_list_box_tests[i] = m_bvh.query(
            m_list_boxes[i],
            [&](int j) {
              if (!model.neighbours(i, j)) partners.push_back(j);
            },
            i);
        std::sort(partners.begin(), partners.end());
        // headroom, so that later rebuilds rarely allocate
        if (partners.capacity() < partners.size() + partners.size() / 4)
          partners.reserve(partners.size() + partners.size() / 2);
      }
    });
    m_timings.traverse = seconds_since(t);
    m_list_valid = true;
    m_list_model = &model;
    m_list_radius = model.params.material.radius;
  }

  // point-pair kernels, each pair (i < j) once, owned by row i
  t = Clock::now();
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 16), [&](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i < range.end(); ++i) {
      m_pairs[i].clear();
      if (m_record) m_row_records[i].clear();
      m_row_kv[i].clear();
      OwnStiffness own;
      if (m_stiffness) {
        m_row_stiff[i].clear();
        m_row_sj[i].clear();
        own.used.fill(0);
      }
      RowStats& row = m_rows[i];
      row = RowStats{};
      if (rebuild) row.box_tests = m_list_box_tests[i];
      const std::vector<int>& partners = m_partners[i];
      const Aabb& box_i = m_boxes[i];
      for (auto it = std::upper_bound(partners.begin(), partners.end(), i); it != partners.end();
           ++it) {
        // most candidates of a wide list are out of reach: tested here, before the kernel's
        // set-up (pair_kernel tests it again)
        if (!box_i.overlaps(m_boxes[*it])) continue;
        if (m_has_velocity && m_stiffness)
          pair_kernel<true, true>(model, i, *it, row, own);
        else if (m_has_velocity)
          pair_kernel<true, false>(model, i, *it, row, own);
        else if (m_stiffness)
          pair_kernel<false, true>(model, i, *it, row, own);
        else
          pair_kernel<false, false>(model, i, *it, row, own);
      }
      if (m_stiffness) {
        // the row's own sums, compacted
        std::vector<PointStiffness>& si = m_row_si[i];
        si.clear();
        for (int a = 0; a < m_points; ++a)
          if (own.used[a]) si.push_back({a, own.s[a]});
      }
    }
  });
  m_timings.kernel = seconds_since(t);

  // per-segment sums in a fixed order: own pairs (i, j > i), then pairs (k < i, i) in
  // ascending k
  t = Clock::now();
  index_incoming_pairs(n);
  const double energy = m_accumulator.run(model, [&](int s, Vector12d& slot) {
    for (const PairForce& pf : m_pairs[s]) slot += pf.force_i;
    for (int q = m_incoming_offset[s]; q < m_incoming_offset[s + 1]; ++q)
      slot += m_pairs[m_incoming[q].k][m_incoming[q].index].force_j;
    return m_rows[s].energy;
  });
  m_accumulator.gather(model, force, 1.0);
  // K v in the same order
  m_kv_valid = m_has_velocity && m_stiffness;
  if (m_kv_valid) {
    m_kv_accumulator.run(model, [&](int s, Vector12d& slot) {
      for (const PairKv& kv : m_row_kv[s]) slot += kv.i;
      for (int q = m_incoming_offset[s]; q < m_incoming_offset[s + 1]; ++q)
        slot += m_row_kv[m_incoming[q].k][m_incoming[q].index].j;
      return 0.0;
    });
    m_kv.setZero(q.size());
    m_kv_accumulator.gather(model, m_kv, 1.0);
    m_kv_velocity = v;
  }
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
    m_stats.min_distance_ratio = std::sqrt(min_d2) / (2 * model.params.material.radius);
  if (m_record)
    for (const auto& rec : m_row_records)
      m_point_pairs.insert(m_point_pairs.end(), rec.begin(), rec.end());
  return energy;
}

void ContactTerm::index_incoming_pairs(int n) {
  // a counting sort of the pairs (k, index) by their j, visited in ascending k: each
  // segment's incoming pairs come out in ascending row
  m_incoming_offset.assign(n + 1, 0);
  for (int k = 0; k < n; ++k)
    for (const PairForce& pf : m_pairs[k]) ++m_incoming_offset[pf.j + 1];
  for (int s = 0; s < n; ++s) m_incoming_offset[s + 1] += m_incoming_offset[s];
  m_incoming.resize(m_incoming_offset[n]);
  m_incoming_fill.assign(m_incoming_offset.begin(), m_incoming_offset.end() - 1);
  for (int k = 0; k < n; ++k)
    for (int p = 0; p < static_cast<int>(m_pairs[k].size()); ++p)
      m_incoming[m_incoming_fill[m_pairs[k][p].j]++] = {k, p};
  if (!m_stiffness) return;
  // the point pairs numbered row by row (they stay in the rows' arrays)
  m_stiff_offset.resize(n + 1);
  m_stiff_offset[0] = 0;
  for (int i = 0; i < n; ++i)
    m_stiff_offset[i + 1] = m_stiff_offset[i] + static_cast<int>(m_row_stiff[i].size());
  // the flat arrays are built when first read (flatten): an evaluation that the next
  // one replaces before any product or linearised step (every step while the knit
  // moves fast) never needs them
  m_flat_valid = false;
}

void ContactTerm::flatten(const Model& model) const {
  if (m_flat_valid || !m_stiffness) return;
  const int n = static_cast<int>(m_stiff_offset.size()) - 1;
  if (n < 0) return;
  // the rows' point pairs copied to one array in order, with what the products read per pair
  const QuadratureTable& quad = model.contact_quad;
  m_flat.resize(m_stiff_offset[n]);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 64), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i < r.end(); ++i) {
      const int ci = model.seg_cp[i];
      const double li = model.rest_length[i];
      FlatPair* out = m_flat.data() + m_stiff_offset[i];
      for (const StiffPair& p : m_row_stiff[i]) {
        const double c2 = -2.0 * li * model.rest_length[p.j] * quad.w[p.a] * quad.w[p.b];
        *out++ = {ci, model.seg_cp[p.j], p.a, p.b, p.dx, p.dy, p.dz, p.kn, p.kt, c2};
      }
    }
  });
  // each segment's incoming point pairs: per incoming segment pair (ascending row k) its
  // run of row k's point pairs
  m_in_offset.assign(n + 1, 0);
  for (int s = 0; s < n; ++s) {
    int count = 0;
    for (int q = m_incoming_offset[s]; q < m_incoming_offset[s + 1]; ++q) {
      const PairForce& pf = m_pairs[m_incoming[q].k][m_incoming[q].index];
      count += pf.stiff_end - pf.stiff_begin;
    }
    m_in_offset[s + 1] = m_in_offset[s] + count;
  }
  m_in_points.resize(m_in_offset[n]);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 64), [&](const tbb::blocked_range<int>& r) {
    for (int s = r.begin(); s < r.end(); ++s) {
      IncomingPoint* out = m_in_points.data() + m_in_offset[s];
      for (int q = m_incoming_offset[s]; q < m_incoming_offset[s + 1]; ++q) {
        const Incoming& in = m_incoming[q];
        const PairForce& pf = m_pairs[in.k][in.index];
        const std::vector<StiffPair>& row = m_row_stiff[in.k];
        for (int t = pf.stiff_begin; t < pf.stiff_end; ++t)
          *out++ = {m_stiff_offset[in.k] + t, row[t].b};
      }
    }
  });
  m_flat_valid = true;
}

void ContactTerm::set_operator_stiffness(bool on) {
  if (on && m_culling != ContactCulling::BVH)
    throw std::logic_error("the contact stiffness operator needs BVH culling");
  m_stiffness = on;
  m_kv_valid = false;
  m_lin_valid = false;
  if (!on) {
    for (auto& row : m_row_stiff) row.clear();
    for (auto& row : m_row_si) row.clear();
    for (auto& row : m_row_sj) row.clear();
    m_stiff_offset.clear();
    m_flat.clear();
    m_in_points.clear();
    m_in_offset.clear();
    m_flat_valid = false;
  }
}

Eigen::Vector3d ContactTerm::pair_product(const FlatPair& p, const double* x) const {
  // f = k n̂ (n̂·u) + kt (u − n̂ (n̂·u)) = kn (Δ·u) Δ + kt u, u = J x the change of
  // Δ = y_j(t_b) − y_i(t_a)
  const std::array<double, 4>& ba = m_basis[p.a];
  const std::array<double, 4>& bb = m_basis[p.b];
  const double* xi = x + 3 * p.ci;
  const double* xj = x + 3 * p.cj;
  double u[3] = {0, 0, 0};
  for (int c = 0; c < 4; ++c)
    for (int d = 0; d < 3; ++d) u[d] += bb[c] * xj[3 * c + d] - ba[c] * xi[3 * c + d];
  const Eigen::Vector3d uv(u[0], u[1], u[2]), delta(p.dx, p.dy, p.dz);
  return (p.kn * delta.dot(uv)) * delta + p.kt * uv;
}

template <class Force, class Slot>
void ContactTerm::segment_product(int s, Force&& force, Slot& slot) const {
  // K x puts B_b f on j's control points and −B_a f on i's
  for (int k = m_stiff_offset[s]; k < m_stiff_offset[s + 1]; ++k) {
    const auto& f = force(k);
    const std::array<double, 4>& ba = m_basis[m_flat[k].a];
    for (int c = 0; c < 4; ++c) slot.template middleRows<3>(3 * c) -= ba[c] * f;
  }
  // the incoming segment pairs in ascending row k, each one run of row k's point pairs
  for (int e = m_in_offset[s]; e < m_in_offset[s + 1]; ++e) {
    const IncomingPoint& in = m_in_points[e];
    const auto& f = force(in.k);
    const std::array<double, 4>& bb = m_basis[in.b];
    for (int c = 0; c < 4; ++c) slot.template middleRows<3>(3 * c) += bb[c] * f;
  }
}

void ContactTerm::add_stiffness_product(const Model& model, const Eigen::VectorXd& x,
                                        Eigen::VectorXd& y) const {
  if (!m_stiffness) return;
  const int rows = std::min<int>(m_num_seg, static_cast<int>(m_stiff_offset.size()) - 1);
  if (rows <= 0) return;  // no evaluation yet
  if (m_kv_valid && x.size() == m_kv_velocity.size() &&
      std::memcmp(x.data(), m_kv_velocity.data(), sizeof(double) * x.size()) == 0) {
    y += m_kv;  // x is the velocity of the last evaluation: its kernels formed K x
    return;
  }
  flatten(model);
  m_stiff_product.resize(m_stiff_offset[rows]);
  // per point pair its force (pair_product), then per segment their sum (segment_product)
  tbb::parallel_for(tbb::blocked_range<int>(0, m_stiff_offset[rows], 256),
                    [&](const tbb::blocked_range<int>& r) {
                      for (int k = r.begin(); k < r.end(); ++k)
                        m_stiff_product[k] = pair_product(m_flat[k], x.data());
                    });
  // per segment, in a fixed order: its own row's pairs (it is i), then the pairs of rows
  // k < s that have it as j, in ascending k
  m_product_accumulator.run(model, [&](int s, Vector12d& slot) {
    if (s < rows)
      segment_product(
          s, [&](int k) { return m_stiff_product[k]; }, slot);
    return 0.0;
  });
  m_product_accumulator.gather(model, y, 1.0);
}

void ContactTerm::add_stiffness_product_rows(const Model& model, const Eigen::VectorXd& x,
                                             const std::vector<int>& segments,
                                             Eigen::VectorXd& y) const {
  if (!m_stiffness) return;
  const int rows = std::min<int>(m_num_seg, static_cast<int>(m_stiff_offset.size()) - 1);
  if (rows <= 0 || segments.empty()) return;
  flatten(model);
  // as add_stiffness_product, each listed segment's pairs taken afresh (a few segments)
  auto force = [&](int k) { return pair_product(m_flat[k], x.data()); };
  for (int s : segments) {
    if (s >= rows) continue;
    Vector12d slot = Vector12d::Zero();
    segment_product(s, force, slot);
    y.segment<12>(3 * model.seg_cp[s]) += slot;
  }
}

void ContactTerm::add_operator_segment_stiffness(const Model& model,
                                                 std::vector<Matrix12d>& blocks) const {
  tbb::parallel_for(tbb::blocked_range<int>(0, static_cast<int>(blocks.size()), 16),
                    [&](const tbb::blocked_range<int>& r) {
                      for (int s = r.begin(); s < r.end(); ++s)
                        add_operator_segment_block(model, s, blocks[s]);
                    });
}

bool ContactTerm::add_operator_segment_block(const Model& /*model*/, int s,
                                             Matrix12d& block) const {
  if (!m_stiffness) return false;
  const int rows = std::min<int>(m_num_seg, static_cast<int>(m_stiff_offset.size()) - 1);
  if (s >= rows) return false;  // (no evaluation yet)
  // while a linearisation is reused, every step's factor asks for the same blocks: each is
  // formed once per exact evaluation and kept
  double local[10][6];
  double(*upper)[6] = local;
  if (m_lin_valid && m_block_state.size() == static_cast<size_t>(m_num_seg)) {
    upper = reinterpret_cast<double(*)[6]>(m_block_cache.data() + 60 * static_cast<size_t>(s));
    char& state = m_block_state[s];
    if (state == 0) state = operator_block_upper(s, upper) ? 2 : 1;
    if (state == 1) return false;
  } else if (!operator_block_upper(s, upper)) {
    return false;
  }
  int uv = 0;
  for (int u = 0; u < 4; ++u)
    for (int v = u; v < 4; ++v, ++uv) {
      const double* m = upper[uv];
      Eigen::Matrix3d sym;
      sym << m[0], m[1], m[2], m[1], m[3], m[4], m[2], m[4], m[5];
      block.block<3, 3>(3 * u, 3 * v) += sym;
      if (v != u) block.block<3, 3>(3 * v, 3 * u) += sym;
    }
  return true;
}

bool ContactTerm::operator_block_upper(int s, double (*upper)[6]) const {
  // Σ_a (b_a b_aᵀ) ⊗ S_a, S_a = Σ over the point pairs at the segment's point a of
  // k n̂n̂ᵀ + kt (I − n̂n̂ᵀ): the kernels summed the 3×3s (6 numbers, symmetric) per point,
  // over its own row and per incoming pair; here those sums are added up, then one
  // Kronecker product per point in contact, its upper triangle of 3×3 blocks, then mirrored
  // (per point pair, the product cost 90 multiply-adds; per point it costs 60)
  std::array<std::array<double, 6>, MAX_CONTACT_POINTS> S;
  std::array<char, MAX_CONTACT_POINTS> used{};
  bool any_used = false;
  for (const PointStiffness& ps : m_row_si[s]) {
    S[ps.point] = ps.s;
    used[ps.point] = 1;
    any_used = true;
  }
  for (int q = m_incoming_offset[s]; q < m_incoming_offset[s + 1]; ++q) {
    const Incoming& in = m_incoming[q];
    const PairForce& pf = m_pairs[in.k][in.index];
    const std::vector<PointStiffness>& sj = m_row_sj[in.k];
    for (int t = pf.sj_begin; t < pf.sj_end; ++t) {
      const PointStiffness& ps = sj[t];
      std::array<double, 6>& m = S[ps.point];
      if (!used[ps.point]) {
        m = ps.s;
        used[ps.point] = 1;
      } else {
        for (int c = 0; c < 6; ++c) m[c] += ps.s[c];
      }
      any_used = true;
    }
  }
  if (!any_used) return false;
  for (int uv = 0; uv < 10; ++uv) std::fill_n(upper[uv], 6, 0.0);
  for (int a = 0; a < m_points; ++a) {
    if (!used[a]) continue;
    const std::array<double, 4>& b = m_basis[a];
    const std::array<double, 6>& m = S[a];
    int uv = 0;
    for (int u = 0; u < 4; ++u)
      for (int v = u; v < 4; ++v, ++uv) {
        const double w = b[u] * b[v];
        for (int e = 0; e < 6; ++e) upper[uv][e] += w * m[e];
      }
  }
  return true;
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
