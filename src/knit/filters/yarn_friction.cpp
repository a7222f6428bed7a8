#include "knit/filters/yarn_friction.hpp"

#include <algorithm>
#include <cmath>

#include "knit/spline/basis.hpp"

namespace knit {

namespace {

// c_k of a pair: B_k(t_j) on j's control points, −B_k(t_i) on i's, merged where shared;
// returns false when the pair is not one of `model`'s
struct Coefficients {
  int n = 0;
  int cp[8];
  double c[8];
};

bool coefficients(const Model& model, const ContactPairRecord& p, Coefficients& out) {
  const int nseg = model.num_seg();
  if (p.seg_i < 0 || p.seg_j < 0 || p.seg_i >= nseg || p.seg_j >= nseg) return false;
  const Eigen::Vector4d bi = bspline_basis(p.t_i), bj = bspline_basis(p.t_j);
  out.n = 0;
  auto add = [&out](int cp, double c) {
    for (int k = 0; k < out.n; ++k)
      if (out.cp[k] == cp) {
        out.c[k] += c;
        return;
      }
    out.cp[out.n] = cp;
    out.c[out.n++] = c;
  };
  for (int a = 0; a < 4; ++a) add(model.seg_cp[p.seg_i] + a, -bi[a]);
  for (int a = 0; a < 4; ++a) add(model.seg_cp[p.seg_j] + a, bj[a]);
  for (int k = 0; k < out.n; ++k)
    if (out.cp[k] >= model.num_cp()) return false;
  return true;
}

Eigen::Vector3d combine(const Coefficients& c, const Eigen::VectorXd& x) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int k = 0; k < c.n; ++k) sum += c.c[k] * x.segment<3>(3 * c.cp[k]);
  return sum;
}

}  // namespace

void YarnFrictionFilter::begin_step(const StepData& start, const Eigen::VectorXd& q_start) {
  m_pairs.clear();
  if (!(m_mu > 0)) return;
  m_pairs = start.contact.pairs;
  m_q_start = q_start;
}

void YarnFrictionFilter::apply(const Model& model, const Eigen::VectorXd& q, Eigen::VectorXd& v,
                               double /*time*/, double h) {
  // the warm start moves to m_kept_before (kept for a step thrown away, reject_step);
  // m_kept is written anew
  m_kept_before.swap(m_kept);
  m_can_reject = true;
  m_h = h;
  m_record = FrictionRecord{};
  m_record.present = true;
  m_rows.clear();
  if (!(m_mu > 0) || m_pairs.empty() || m_q_start.size() != q.size()) {
    m_kept.clear();
    return;
  }
  // the pairs' rows: control points, coefficients, the mass their impulse moves, the cone,
  // the normal and how fast the pair's points moved against each other
  for (const ContactPairRecord& p : m_pairs) {
    const double bound = m_mu * std::max(p.normal_force, 0.0) * h;
    if (!(bound > 0)) continue;
    Coefficients co;
    if (!coefficients(model, p, co)) continue;
    Row row;
    row.seg_i = p.seg_i;
    row.seg_j = p.seg_j;
    row.n = co.n;
    for (int k = 0; k < co.n; ++k) {
      row.cp[k] = co.cp[k];
      row.c[k] = co.c[k];
      row.cm[k] = co.c[k] / model.mass[co.cp[k]];
      row.inv_m += co.c[k] * row.cm[k];
    }
    if (!(row.inv_m > 0)) continue;
    row.bound = bound;
    const Eigen::Vector3d delta = combine(co, q);
    const double len = delta.norm();
    row.normal = len > 0 ? Eigen::Vector3d(delta / len) : p.normal;
    row.rate = (delta - combine(co, m_q_start)) / h;
    row.lambda.setZero();
    m_rows.push_back(row);
  }
  m_dv.setZero(v.size());
  // warm start: each pair that was in contact in the last step starts from its impulse
  // there, in the new tangent plane and cone (both lists are sorted by segment pair)
  auto kept = m_kept_before.begin();
  for (Row& row : m_rows) {
    const auto key = std::pair{row.seg_i, row.seg_j};
    while (kept != m_kept_before.end() && std::pair{kept->seg_i, kept->seg_j} < key) ++kept;
    if (kept == m_kept_before.end() || std::pair{kept->seg_i, kept->seg_j} != key) continue;
    Eigen::Vector3d lambda = kept->lambda - kept->lambda.dot(row.normal) * row.normal;
    const double norm = lambda.norm();
    if (norm > row.bound) lambda *= row.bound / norm;
    row.lambda = lambda;
    for (int k = 0; k < row.n; ++k) m_dv.segment<3>(3 * row.cp[k]) += row.cm[k] * lambda;
  }
  // projected Gauss–Seidel on the accumulated impulses; a pair's rate now is its rate over
  // the step plus what the impulses so far changed (positions move by h Δv)
  auto rate_now = [this](const Row& row) {
    Eigen::Vector3d u = row.rate;
    for (int k = 0; k < row.n; ++k) u += row.c[k] * m_dv.segment<3>(3 * row.cp[k]);
    return Eigen::Vector3d(u - u.dot(row.normal) * row.normal);
  };
  int pass = 0;
  for (; pass < PASSES; ++pass) {
    double change = 0, total = 0;
    for (Row& row : m_rows) {
      Eigen::Vector3d lambda = row.lambda - rate_now(row) / row.inv_m;
      lambda -= lambda.dot(row.normal) * row.normal;
      const double norm = lambda.norm();
      if (norm > row.bound) lambda *= row.bound / norm;
      const Eigen::Vector3d d = lambda - row.lambda;
      if (d.squaredNorm() == 0) continue;
      row.lambda = lambda;
      for (int k = 0; k < row.n; ++k) m_dv.segment<3>(3 * row.cp[k]) += row.cm[k] * d;
      change = std::max(change, d.norm() * row.inv_m);  // the largest rate change
      total = std::max(total, lambda.norm() * row.inv_m);
    }
    if (!(change > TOLERANCE * total)) break;
  }
  m_record.passes = std::min(pass + 1, PASSES);
  v += m_dv;
  m_kept.clear();
  for (const Row& row : m_rows) m_kept.push_back({row.seg_i, row.seg_j, row.lambda});
  // what it did: pairs, stuck ones (inside their cones), energy dissipated, force
  for (const Row& row : m_rows) {
    ++m_record.pairs;
    const double norm = row.lambda.norm();
    if (norm < row.bound * (1 - 1e-9)) ++m_record.stuck;
    m_record.work -= row.lambda.dot(rate_now(row));
    m_record.force += norm / h;
  }
  m_record.work = std::max(m_record.work, 0.0);  // rounding of stopped pairs' −λ · 0
}

bool YarnFrictionFilter::adjust_positions(const Model& /*model*/, Eigen::VectorXd& q) const {
  if (m_rows.empty() || m_dv.size() != q.size()) return false;
  q += m_h * m_dv;
  return true;
}

void YarnFrictionFilter::record(StepData& data) const {
  data.friction = m_record;
}

void YarnFrictionFilter::reject_step() {
  if (!m_can_reject) return;
  m_can_reject = false;
  m_kept.swap(m_kept_before);
}

}  // namespace knit
