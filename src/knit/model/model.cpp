#include "knit/model/model.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace knit {

bool Model::has_stitches() const {
  for (const auto& s : stitch)
    if (s.row >= 0) return true;
  return false;
}

double Model::total_length() const {
  double sum = 0;
  for (double l : rest_length) sum += l;
  return sum;
}

double segment_arclength(const Vector12d& x, const QuadratureTable& quad) {
  double len = 0;
  for (int k = 0; k < quad.size(); ++k) len += quad.w[k] * combine(x, quad.db[k]).norm();
  return len;
}

int ModelBuilder::add_yarn(const Eigen::Matrix3Xd& control_points) {
  if (control_points.cols() < 4)
    throw std::invalid_argument("yarn " + std::to_string(m_yarns.size()) +
                                ": a cubic B-spline needs at least 4 control points, got " +
                                std::to_string(control_points.cols()));
  if (!control_points.allFinite())
    throw std::invalid_argument("yarn " + std::to_string(m_yarns.size()) +
                                ": control points must be finite numbers");
  m_yarns.push_back(control_points);
  return static_cast<int>(m_yarns.size()) - 1;
}

int ModelBuilder::num_segments() const {
  int n = 0;
  for (const auto& y : m_yarns) n += static_cast<int>(y.cols()) - 3;
  return n;
}

int ModelBuilder::segment_index(int yarn, int local) const {
  if (yarn < 0 || yarn >= num_yarns())
    throw std::out_of_range("yarn " + std::to_string(yarn) + " does not exist (there are " +
                            std::to_string(num_yarns()) + ")");
  const int nseg = static_cast<int>(m_yarns[yarn].cols()) - 3;
  if (local < 0 || local >= nseg)
    throw std::out_of_range("segment " + std::to_string(local) + " does not exist on yarn " +
                            std::to_string(yarn) + " (it has " + std::to_string(nseg) +
                            " segments)");
  int base = 0;
  for (int y = 0; y < yarn; ++y) base += static_cast<int>(m_yarns[y].cols()) - 3;
  return base + local;
}

Eigen::VectorXd ModelBuilder::positions() const {
  int ncp = 0;
  for (const auto& y : m_yarns) ncp += static_cast<int>(y.cols());
  Eigen::VectorXd q(3 * ncp);
  int c = 0;
  for (const auto& y : m_yarns)
    for (int k = 0; k < y.cols(); ++k, ++c) q.segment<3>(3 * c) = y.col(k);
  return q;
}

Model ModelBuilder::build(const Params& params, double rest_scale) const {
  if (m_yarns.empty()) throw std::invalid_argument("a model needs at least one yarn");
  Model m;
  m.params = params;
  m.quad = simpson_table(params.discretisation.quadrature_points);
  m.contact_quad = midpoint_table(params.discretisation.contact_points);
  const Eigen::VectorXd q = positions();
  int cp = 0, seg = 0;
  for (int y = 0; y < num_yarns(); ++y) {
    YarnInfo info;
    info.cp_begin = cp;
    info.cp_end = cp + static_cast<int>(m_yarns[y].cols());
    info.seg_begin = seg;
    info.seg_end = seg + info.num_cp() - 3;
    for (int i = 0; i < info.num_seg(); ++i) {
      m.seg_cp.push_back(cp + i);
      m.seg_yarn.push_back(y);
    }
    m.yarns.push_back(info);
    cp = info.cp_end;
    seg = info.seg_end;
  }
  // rest lengths and lumped mass M_k = μ Σ_i ℓ_i ∫B_{k−i} (unshrunk lengths: the yarn's
  // mass does not change when relaxation shrinks its rest length)
  const double int_b[4] = {1.0 / 24, 11.0 / 24, 11.0 / 24, 1.0 / 24};
  m.rest_length.resize(seg);
  m.mass = Eigen::VectorXd::Zero(cp);
  for (int i = 0; i < seg; ++i) {
    const double len = segment_arclength(gather_segment(q, m.seg_cp[i]), m.quad);
    if (!(len > 0))
      throw std::invalid_argument("segment " + std::to_string(i) +
                                  " has zero length (its 4 control points coincide)");
    m.rest_length[i] = rest_scale * len;
    for (int a = 0; a < 4; ++a) m.mass[m.seg_cp[i] + a] += params.material.density * len * int_b[a];
  }
  m.inv_mass3.resize(3 * cp);
  for (int k = 0; k < cp; ++k) m.inv_mass3.segment<3>(3 * k).setConstant(1.0 / m.mass[k]);
  apply_end_mass_floor(m, params.discretisation.end_mass_floor);
  m.stitch = m_stitch;
  if (m.stitch.empty()) m.stitch.assign(seg, StitchCoord{});
  if (static_cast<int>(m.stitch.size()) != seg)
    throw std::invalid_argument("stitch coordinates given for " + std::to_string(m.stitch.size()) +
                                " segments, the model has " + std::to_string(seg));
  auto check_point = [&](const YarnPoint& p, const std::string& what) {
    if (p.segment < 0 || p.segment >= seg)
      throw std::out_of_range(what + ": segment " + std::to_string(p.segment) +
                              " does not exist (the model has " + std::to_string(seg) +
                              " segments)");
    if (!(p.t >= 0 && p.t <= 1))
      throw std::out_of_range(what + ": parameter t must lie in [0,1], got " + std::to_string(p.t));
  };
  for (size_t k = 0; k < m_pins.size(); ++k) check_point(m_pins[k].at, "pin " + std::to_string(k));
  for (size_t k = 0; k < m_glues.size(); ++k) {
    check_point(m_glues[k].a, "glue " + std::to_string(k));
    check_point(m_glues[k].b, "glue " + std::to_string(k));
  }
  m.pins = m_pins;
  m.glues = m_glues;
  for (size_t k = 0; k < m_clamps.size(); ++k) {
    Clamp c = m_clamps[k];
    if (c.name.empty()) c.name = "clamp" + std::to_string(k);
    if (c.points.empty() && c.control_points.empty())
      throw std::invalid_argument("clamp " + c.name + ": it holds no points");
    for (size_t p = 0; p < c.points.size(); ++p)
      check_point(c.points[p], "clamp " + c.name + " point " + std::to_string(p));
    std::vector<int> sorted = c.control_points;
    std::sort(sorted.begin(), sorted.end());
    for (size_t k = 0; k < sorted.size(); ++k) {
      if (sorted[k] < 0 || sorted[k] >= cp)
        throw std::out_of_range("clamp " + c.name + ": control point " + std::to_string(sorted[k]) +
                                " does not exist (the model has " + std::to_string(cp) + ")");
      if (k > 0 && sorted[k] == sorted[k - 1])
        throw std::invalid_argument("clamp " + c.name + ": control point " +
                                    std::to_string(sorted[k]) + " is held twice");
    }
    c.rest.clear();
    c.centre.setZero();
    for (const YarnPoint& p : c.points) c.rest.push_back(point_position(m, q, p));
    for (int k : c.control_points) c.rest.push_back(q.segment<3>(3 * k));
    for (const Eigen::Vector3d& r : c.rest) c.centre += r;
    c.centre /= static_cast<double>(c.rest.size());
    for (size_t f = 1; f < c.keyframes.size(); ++f)
      if (!(c.keyframes[f].time > c.keyframes[f - 1].time))
        throw std::invalid_argument("clamp " + c.name + ": keyframe times must increase");
    m.clamps.push_back(std::move(c));
  }
  for (const Glue& g : m_glues) {
    const int k = GLUE_CONTACT_EXCLUSION;
    for (int i = std::max(0, g.a.segment - k); i <= std::min(seg - 1, g.a.segment + k); ++i)
      for (int j = std::max(0, g.b.segment - k); j <= std::min(seg - 1, g.b.segment + k); ++j)
        if (i != j) m.contact_exclusions.emplace_back(std::min(i, j), std::max(i, j));
  }
  std::sort(m.contact_exclusions.begin(), m.contact_exclusions.end());
  m.contact_exclusions.erase(std::unique(m.contact_exclusions.begin(), m.contact_exclusions.end()),
                             m.contact_exclusions.end());
  return m;
}

const std::vector<std::string>& relax_setting_params() {
  static const std::vector<std::string> names = {
      "integrator",    "time_step",         "implicit_bending", "contact_solve_tolerance",
      "contact_reuse", "max_step_halvings", "contact_points",   "end_mass_floor",
      "k_global",      "alpha_small",       "alpha_large"};
  return names;
}

void apply_end_mass_floor(Model& m, double fraction) {
  if (!(fraction > 0)) return;
  for (const YarnInfo& y : m.yarns) {
    const int n = y.num_cp();
    if (n < 8) continue;  // no interior to speak of
    double interior = 0;
    for (int k = y.cp_begin + 3; k < y.cp_end - 3; ++k) interior += m.mass[k];
    interior /= n - 6;
    for (int k : {y.cp_begin, y.cp_begin + 1, y.cp_end - 2, y.cp_end - 1}) {
      m.mass[k] = std::max(m.mass[k], fraction * interior);
      m.inv_mass3.segment<3>(3 * k).setConstant(1.0 / m.mass[k]);
    }
  }
}

Keyframe interpolate_keyframes(const std::vector<Keyframe>& keyframes, double time) {
  if (keyframes.empty()) return {};
  if (time <= keyframes.front().time) return keyframes.front();
  if (time >= keyframes.back().time) return keyframes.back();
  size_t f = 1;
  while (keyframes[f].time < time) ++f;
  const Keyframe& a = keyframes[f - 1];
  const Keyframe& b = keyframes[f];
  const double s = (time - a.time) / (b.time - a.time);
  Keyframe k;
  k.time = time;
  k.translation = (1 - s) * a.translation + s * b.translation;
  k.rotation = a.rotation.slerp(s, b.rotation);
  return k;
}

void keyframe_rates(const std::vector<Keyframe>& keyframes, double time, Eigen::Vector3d& velocity,
                    Eigen::Vector3d& omega) {
  velocity.setZero();
  omega.setZero();
  if (keyframes.size() < 2 || time < keyframes.front().time || time >= keyframes.back().time)
    return;
  size_t f = 1;
  while (keyframes[f].time <= time) ++f;
  const Keyframe& a = keyframes[f - 1];
  const Keyframe& b = keyframes[f];
  const double dt = b.time - a.time;
  velocity = (b.translation - a.translation) / dt;
  // slerp(a, b, s) = (b a⁻¹)^s a, the shortest way: ω = axis · angle / dt of b a⁻¹
  Eigen::Quaterniond rel = b.rotation * a.rotation.conjugate();
  if (rel.w() < 0) rel.coeffs() = -rel.coeffs();
  const Eigen::AngleAxisd aa(rel);
  omega = aa.axis() * (aa.angle() / dt);
}

Keyframe Clamp::pose(double time) const {
  return interpolate_keyframes(keyframes, time);
}

Model scale_rest_lengths(const Model& model, double scale) {
  Model m = model;
  for (double& l : m.rest_length) l *= scale;
  return m;
}

Eigen::Vector3d point_position(const Model& model, const Eigen::VectorXd& q, const YarnPoint& p) {
  return combine(gather_segment(q, model.seg_cp[p.segment]), bspline_basis(p.t));
}

}  // namespace knit
