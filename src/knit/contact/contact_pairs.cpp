#include "knit/contact/contact_term.hpp"

// ContactTerm's BVH traversal and pair kernel (add_force_bvh, pair_kernel), and the
// index of each segment's incoming pairs.
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

namespace {

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

}  // namespace

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

}  // namespace knit
