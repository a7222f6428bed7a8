#include "knit/contact/contact_term.hpp"

// ContactTerm's linearised reuse (add_force_linearised) and its operator stiffness: the
// flat pair arrays, the stiffness products and the per-segment blocks.
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

}  // namespace knit
