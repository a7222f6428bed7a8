#include "knit/solver/simulator.hpp"
#include "knit/solver/terms.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "knit/constraints/clamp.hpp"
#include "knit/constraints/groups.hpp"
#include "knit/constraints/inextensibility.hpp"
#include "knit/contact/contact_term.hpp"
#include "knit/contact/crossings.hpp"
#include "knit/energy/bending.hpp"
#include "knit/energy/global_damping.hpp"
#include "knit/energy/gravity.hpp"
#include "knit/energy/length.hpp"
#include "knit/objects/object.hpp"
#include "knit/objects/object_penalty.hpp"

namespace knit {

namespace {

class ScopedTimer {
 public:
  explicit ScopedTimer(double& sink) : m_sink(sink), m_start(std::chrono::steady_clock::now()) {}
  ~ScopedTimer() { stop(); }
  /// Adds the time since construction to the sink now (once; the destructor then adds nothing).
  void stop() {
    if (m_stopped) return;
    m_stopped = true;
    m_sink += std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
  }

 private:
  double& m_sink;
  bool m_stopped = false;
  std::chrono::steady_clock::time_point m_start;
};

// How far one step moved the control points (cm): the largest displacement relative to
// the neighbouring control point on the same yarn (how much the step deformed the yarn —
// a yarn moving rigidly, falling or swinging, scores ~0 however fast it goes), which
// control point that was, and the largest displacement of any control point.
struct Travel {
  double relative = 0;
  int relative_cp = 0;
  double absolute = 0;
};

Travel step_travel(const Model& model, const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  double worst_rel = 0, worst_abs = 0;
  int which = 0;
  for (const YarnInfo& y : model.yarns) {
    Eigen::Vector3d prev = b.segment<3>(3 * y.cp_begin) - a.segment<3>(3 * y.cp_begin);
    worst_abs = std::max(worst_abs, prev.squaredNorm());
    for (int k = y.cp_begin + 1; k < y.cp_end; ++k) {
      const Eigen::Vector3d d = b.segment<3>(3 * k) - a.segment<3>(3 * k);
      worst_abs = std::max(worst_abs, d.squaredNorm());
      const double rel = (d - prev).squaredNorm();
      if (rel > worst_rel) {
        worst_rel = rel;
        which = k;
      }
      prev = d;
    }
  }
  return {std::sqrt(worst_rel), which, std::sqrt(worst_abs)};
}

}  // namespace

const char* status_word(StepStatus status) {
  switch (status) {
    case StepStatus::OK:
      return "ok";
    case StepStatus::NON_FINITE:
      return "unstable";
    case StepStatus::PROJECTION_FAILED:
      return "projection_failed";
    case StepStatus::INTERRUPTED:
      return "interrupted";
    case StepStatus::NOT_CONVERGED:
      return "not_converged";
    case StepStatus::CROSSED:
      return "crossed";
  }
  return "unknown";
}

Simulator::Simulator(Model model) : Simulator(model, default_terms(model)) {}

Simulator::Simulator(Model model, std::vector<std::unique_ptr<Term>> terms)
    : m_model(with_constraint_groups(std::move(model))),
      m_terms(std::move(terms)),
      m_projection(m_model) {
  for (auto& term : m_terms) enable_operator_stiffness(*term);
}

void Simulator::add_term(std::unique_ptr<Term> term) {
  enable_operator_stiffness(*term);
  term->set_reuse_scale(m_reuse_scale);
  m_terms.push_back(std::move(term));
  m_cached = false;
  m_kept_valid = false;  // the kept matrix lacks the new term's stiffness
}

void Simulator::set_reuse_scale(double scale) {
  if (!std::isfinite(scale) || !(scale > 0))
    throw std::invalid_argument("reuse scale = " + short_number(scale) +
                                ": expected a finite number > 0");
  m_reuse_scale = scale;
  for (auto& term : m_terms) term->set_reuse_scale(scale);
}

void Simulator::enable_operator_stiffness(Term& term) {
  if (m_model.params.solver.integrator != Integrator::IMEX_CONTACT ||
      !term.has_operator_stiffness())
    return;
  term.set_operator_stiffness(true);
  m_has_operator_terms = true;
}

bool Simulator::implicit(const Term& term) const {
  const Integrator integrator = m_model.params.solver.integrator;
  return is_imex(integrator) && (term.has_stiffness() || (integrator == Integrator::IMEX_CONTACT &&
                                                          term.has_operator_stiffness()));
}

void Simulator::add_operator_product(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  for (const auto& term : m_terms)
    if (term->has_operator_stiffness() && implicit(*term))
      term->add_stiffness_product(m_model, x, y);
}

void Simulator::band_product(const Eigen::VectorXd& x, double h2, Eigen::VectorXd& y) const {
  // (M + h² Σ blocks) x
  y = m_mass3.cwiseProduct(x);
  add_blocks_product(x, h2, y);
}

void Simulator::pack_blocks() {
  // each block's upper triangle row by row (78 numbers): the product below reads half of
  // what the full blocks hold, and it is bound by that reading
  const int n_seg = m_model.num_seg();
  m_packed.resize(static_cast<size_t>(n_seg) * PACKED);
  tbb::parallel_for(tbb::blocked_range<int>(0, n_seg, 256), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i < r.end(); ++i) {
      double* p = m_packed.data() + static_cast<size_t>(i) * PACKED;
      for (int a = 0; a < 12; ++a)
        for (int b = a; b < 12; ++b) *p++ = m_blocks[i](a, b);
    }
  });
}

void Simulator::add_blocks_product(const Eigen::VectorXd& x, double h2, Eigen::VectorXd& y) const {
  const int n_seg = m_model.num_seg();
  auto add = [&](int i) {
    const double* p = m_packed.data() + static_cast<size_t>(i) * PACKED;
    const int base = 3 * m_model.seg_cp[i];
    const double* xs = x.data() + base;
    double acc[12] = {};
    for (int a = 0; a < 12; ++a) {
      const double xa = xs[a];
      double sum = *p++ * xa;
      for (int b = a + 1; b < 12; ++b, ++p) {
        sum += *p * xs[b];
        acc[b] += *p * xa;
      }
      acc[a] += sum;
    }
    double* ys = y.data() + base;
    for (int a = 0; a < 12; ++a) ys[a] += h2 * acc[a];
  };
  if (!m_seg_ascending) {
    for (int i = 0; i < n_seg; ++i) add(i);
    return;
  }
  // chunks of consecutive segments in parallel, each but its first three segments (which
  // may share control points with the chunk before); those three per chunk after, in turn
  constexpr int CHUNK = 512;
  const int chunks = (n_seg + CHUNK - 1) / CHUNK;
  tbb::parallel_for(
      tbb::blocked_range<int>(0, chunks, 1),
      [&](const tbb::blocked_range<int>& r) {
        for (int c = r.begin(); c < r.end(); ++c)
          for (int i = c * CHUNK + (c > 0 ? 3 : 0); i < std::min(n_seg, (c + 1) * CHUNK); ++i)
            add(i);
      },
      tbb::simple_partitioner());
  for (int c = 1; c < chunks; ++c)
    for (int i = c * CHUNK; i < std::min(n_seg, c * CHUNK + 3); ++i) add(i);
}

void Simulator::add_filter(std::unique_ptr<VelocityFilter> filter) {
  m_filters.push_back(std::move(filter));
}

double Simulator::compute_forces(const Eigen::VectorXd& q, const Eigen::VectorXd& v, double time,
                                 Eigen::VectorXd& force) {
  force.setZero(q.size());
  double e = 0;
  for (auto& term : m_terms) {
    ScopedTimer timer(m_data.stage_seconds[std::string(term->name())]);
    e += term->add_force(m_model, q, v, time, force);
  }
  return e;
}

namespace {

// Σ_k f_k over the control points of a stacked force vector
Eigen::Vector3d net_force(const Eigen::VectorXd& f) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 0; k + 2 < f.size(); k += 3) sum += f.segment<3>(k);
  return sum;
}

bool same_bits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

}  // namespace

void Simulator::forward(const State& state) {
  forward(state, std::numeric_limits<double>::quiet_NaN(), false);
}

bool Simulator::can_leave_out_explicit() const {
  if (!is_imex(m_model.params.solver.integrator)) return false;
  // a step with a stiffness block solves for v⁺; without one it moves q by the midpoint's
  // velocity, which needs every force at the start
  bool any_stiffness = false;
  for (const auto& term : m_terms) {
    any_stiffness = any_stiffness || term->has_stiffness();
    if (!implicit(*term) && term->reads_velocity()) return false;
  }
  return any_stiffness;
}

void Simulator::forward(const State& state, double known_violation, bool lean) {
  if (m_cached && state.time == m_cache_time && same_bits(state.q, m_cache_q) &&
      same_bits(state.v, m_cache_v)) {
    if (!lean && !m_left_out.empty()) complete_records(state);
    return;
  }
  lean = lean && can_leave_out_explicit();
  m_left_out.clear();
  // the same evaluation as compute_forces, term by term into one vector (so the force is
  // bitwise the one a step's first evaluation gives), recording each term's share
  m_force0.setZero(state.q.size());
  m_data.terms.resize(m_terms.size());
  // reset the contact record but keep its pair list's storage (no allocation per step)
  // (the contact term rebuilds the list only when it describes another evaluation)
  std::vector<ContactPairRecord> pairs = std::move(m_data.contact.pairs);
  const long long pairs_of = m_data.contact.pairs_of;
  m_data.contact = ContactRecord{};
  m_data.contact.pairs = std::move(pairs);
  m_data.contact.pairs_of = pairs_of;
  m_data.objects.resize(m_model.objects.size());
  for (size_t k = 0; k < m_model.objects.size(); ++k)
    m_data.objects[k] = ObjectRecord{m_model.objects[k]->name};
  m_data.force_residual = std::numeric_limits<double>::quiet_NaN();
  m_data.force_residual_peak = {};
  m_data.static_constraints.clear();
  double e = 0;
  Eigen::Vector3d before = Eigen::Vector3d::Zero();
  // with the IMEX integrator the implicit terms' force at q is also kept on its own
  const bool imex = is_imex(m_model.params.solver.integrator);
  if (imex) m_force_implicit.setZero(state.q.size());
  constexpr double NaN = std::numeric_limits<double>::quiet_NaN();
  for (size_t t = 0; t < m_terms.size(); ++t) {
    Term& term = *m_terms[t];
    TermRecord& rec = m_data.terms[t];
    rec.name = std::string(term.name());
    if (lean && !implicit(term)) {
      // the step takes it at its midpoint alone: left for complete_records
      rec.energy = NaN;
      rec.net_force = Eigen::Vector3d::Constant(NaN);
      m_left_out.push_back(t);
      continue;
    }
    {
      ScopedTimer timer(m_data.stage_seconds[std::string(term.name())]);
      if (imex && implicit(term)) {
        m_force_term.setZero(state.q.size());
        rec.energy = term.add_force(m_model, state.q, state.v, state.time, m_force_term);
        m_force_implicit += m_force_term;
        m_force0 += m_force_term;
      } else {
        rec.energy = term.add_force(m_model, state.q, state.v, state.time, m_force0);
      }
    }
    ScopedTimer timer(m_data.stage_seconds["record"]);
    e += rec.energy;
    const Eigen::Vector3d after = net_force(m_force0);
    rec.net_force = after - before;
    before = after;
    term.record(m_data);
  }
  m_data.time = state.time;
  m_recorded_energy = e;
  m_data.potential_energy = m_left_out.empty() ? e : NaN;
  m_data.kinetic_energy = kinetic_energy(state);
  m_data.max_violation = std::isnan(known_violation) ? max_violation(state) : known_violation;
  m_cache_q = state.q;
  m_cache_v = state.v;
  m_cache_time = state.time;
  m_cached = true;
}

void Simulator::complete_records(const State& state) {
  double e = m_recorded_energy;
  for (size_t t : m_left_out) {
    Term& term = *m_terms[t];
    TermRecord& rec = m_data.terms[t];
    {
      ScopedTimer timer(m_data.stage_seconds[std::string(term.name())]);
      m_force_term.setZero(state.q.size());
      rec.energy = term.add_force(m_model, state.q, state.v, state.time, m_force_term);
    }
    ScopedTimer timer(m_data.stage_seconds["record"]);
    m_force0 += m_force_term;
    rec.net_force = net_force(m_force_term);
    e += rec.energy;
    term.record(m_data);
  }
  m_left_out.clear();
  m_recorded_energy = e;
  m_data.potential_energy = e;
}

void Simulator::unconstrained_step(const State& s, double h, Eigen::VectorXd& q_out,
                                   Eigen::VectorXd& v_out) {
  const Eigen::VectorXd& inv_m = m_model.inv_mass3;
  forward(s);
  m_qmid = s.q + 0.5 * h * s.v;
  m_vmid = s.v + 0.5 * h * inv_m.cwiseProduct(m_force0);
  compute_forces(m_qmid, m_vmid, s.time + 0.5 * h, m_force);
  q_out = s.q + h * m_vmid;
  v_out = s.v + h * inv_m.cwiseProduct(m_force);
}

bool Simulator::imex_step(const State& s, double h, Eigen::VectorXd& q_out,
                          Eigen::VectorXd& v_out) {
  const Eigen::VectorXd& inv_m = m_model.inv_mass3;
  // every term's force at (q, v), recorded (the explicit ones only where the records need
  // them: set_lean_records); the implicit terms' also on its own
  forward(s, std::numeric_limits<double>::quiet_NaN(), m_lean);
  // with contact reuse and no length rows, the matrix M + h² K (its stiffness blocks, its
  // factor, the glues' W and S) is kept while every control point stays within the reuse
  // distance of where it was formed: linearly implicit Euler with a lagged Jacobian, the
  // contact linearisation's counterpart (docs/model.md §5.2)
  const double reuse =
      m_reuse_scale * m_model.params.solver.contact_reuse * m_model.params.material.radius;
  bool keep = false;
  if (reuse > 0 && !m_model.params.solver.length_constraints && m_kept_valid && h == m_kept_h &&
      m_kept_q.size() == s.q.size()) {
    double moved2 = 0;
    for (Eigen::Index k = 0; k + 2 < s.q.size(); k += 3)
      moved2 = std::max(moved2, (s.q.segment<3>(k) - m_kept_q.segment<3>(k)).squaredNorm());
    keep = moved2 <= reuse * reuse;
  }
  m_data.matrix_kept = keep;
  m_data.reuse_scale = m_reuse_scale;
  // the implicit terms' stiffness at q, summed
  bool any = keep && m_kept_any;
  if (!keep) {
    ScopedTimer timer(m_data.stage_seconds["stiffness"]);
    for (auto& term : m_terms) {
      if (!term->has_stiffness()) continue;
      term->segment_stiffness(m_model, s.q, any ? m_term_blocks : m_blocks);
      if (any)
        for (size_t i = 0; i < m_blocks.size(); ++i) m_blocks[i] += m_term_blocks[i];
      any = true;
    }
  }
  // the midpoint of the explicit midpoint rule, from every term's force (the implicit ones
  // too, so that a state at rest stays at rest), where only the explicit terms are evaluated
  m_qmid = s.q + 0.5 * h * s.v;
  m_vmid = s.v + 0.5 * h * inv_m.cwiseProduct(m_force0);
  m_force.setZero(s.q.size());
  for (auto& term : m_terms) {
    if (implicit(*term)) continue;
    ScopedTimer timer(m_data.stage_seconds[std::string(term->name())]);
    term->add_force(m_model, m_qmid, m_vmid, s.time + 0.5 * h, m_force);
  }
  // the length constraints in the solve, as a stiff penalty on their linearisation
  if (m_model.params.solver.length_constraints) {
    if (!any) m_blocks.assign(m_model.num_seg(), Matrix12d::Zero());
    any = true;
    ScopedTimer timer(m_data.stage_seconds["length_rows"]);
    add_length_rows(s, h);
  }
  // v⁺ = v + h M⁻¹ (f_E(mid) + f_I(q⁺)), f_I(q⁺) ≈ f_I(q) − K (q⁺ − q), q⁺ = q + h v⁺:
  // (M + h² K) Δv = h (f_E(mid) + f_I(q)) − h² K v
  if (!any) {
    v_out = s.v + h * inv_m.cwiseProduct(m_force);
    q_out = s.q + h * m_vmid;
    return true;
  }
  ScopedTimer timer(m_data.stage_seconds["implicit"]);
  build_solve_constraints();
  if (!keep) {
    m_kept_valid = false;
    // with operator terms the factor preconditions their solve: it gets their stiffness on
    // each segment's own control points as its blocks are summed (a hanging 12×12 at
    // h = 1.6e-3 s: 3.8 iterations per step at a tolerance of 1e-2 with them, 12.5 without)
    StiffSolver::ExtraBlock operator_blocks;
    if (m_has_operator_terms)
      operator_blocks = [&](int i, Matrix12d& block) {
        bool added = false;
        for (const auto& term : m_terms)
          if (term->has_operator_stiffness() && implicit(*term))
            added |= term->add_operator_segment_block(m_model, i, block);
        return added;
      };
    {
      ScopedTimer factor_timer(m_data.stage_seconds["implicit_factor"]);
      if (!m_stiff.factor(m_model, m_blocks, h * h, m_fixed_dofs, operator_blocks)) return false;
      pack_blocks();
    }
    if (reuse > 0 && !m_model.params.solver.length_constraints) {
      m_kept_valid = true;
      m_kept_any = any;
      m_kept_h = h;
      m_kept_q = s.q;
    }
  }
  ScopedTimer rhs_timer(m_data.stage_seconds["implicit_rhs"]);
  m_rhs = h * (m_force + m_force_implicit);
  add_blocks_product(s.v, -(h * h), m_rhs);
  // the length rows' −ρ ∇C C / h (their −ρ ∇C ∇Cᵀ v is in the blocks' product above)
  for (size_t i = 0; i < m_len_c.size(); ++i)
    m_rhs.segment<12>(3 * m_model.seg_cp[i]) -= (m_len_rho[i] * m_len_c[i] / h) * m_len_grad[i];
  if (m_has_operator_terms) {
    // − h² K_op v, the operator terms' share of − h² K v
    m_cg_kx.setZero(s.q.size());
    add_operator_product(s.v, m_cg_kx);
    m_rhs -= (h * h) * m_cg_kx;
  }
  // a clamped control point's Δv takes it to the clamp's target at t + h
  m_b_fixed.resize(m_fixed_dofs.size());
  for (size_t k = 0; k < m_fixed_dofs.size(); ++k) m_b_fixed[k] = m_rhs[m_fixed_dofs[k]];
  for (const ClampedPoint& c : m_clamped) {
    const Eigen::Vector3d target = c.group->clamp().target(c.index, s.time + h);
    m_rhs.segment<3>(3 * c.cp) = (target - s.q.segment<3>(3 * c.cp)) / h - s.v.segment<3>(3 * c.cp);
  }
  rhs_timer.stop();
  m_data.solve_iterations = 0;
  m_data.solve_residual = 0;
  m_glue_mu.resize(0);
  const bool cg = m_has_operator_terms && m_model.params.solver.contact_solve_tolerance > 0;
  if (cg || m_glue_rows.empty()) {
    m_stiff.solve(m_rhs, m_dv);
    if (cg) {
      ScopedTimer cg_timer(m_data.stage_seconds["implicit_cg"]);
      solve_with_operator(s, h);
    }
    ScopedTimer glue_timer(m_data.stage_seconds["implicit_glue"]);
    hold_glues_in_solve(s, h, m_dv, keep, false);
  } else {
    // the glues between the factor's two halves: one backward solve, not two
    m_stiff.solve_forward(m_rhs, m_dv);
    {
      ScopedTimer glue_timer(m_data.stage_seconds["implicit_glue"]);
      hold_glues_in_solve(s, h, m_dv, keep, true);
    }
    m_stiff.backward(m_dv);
  }
  v_out = s.v + m_dv;
  q_out = s.q + h * v_out;
  ScopedTimer record_timer(m_data.stage_seconds["implicit_record"]);
  record_solve_forces(q_out, s.time + h, h);
  return true;
}

void Simulator::add_length_rows(const State& s, double h) {
  // Left to the projection after the solve (which moves the yarn in the metric M, not in
  // M + h² K), the length constraints make a rest of every q where the solve's response to
  // the force, (M + h² K)⁻¹ h f, lies along M⁻¹ ∇Cᵀ: the projection takes back what the
  // solve moved, and a spurious force h² K M⁻¹ ∇Cᵀ λ is left standing, large where a yarn
  // under tension has stiff contact in K. Held in the solve, ∇C_i (v + Δv) = −C_i / h, the
  // constraints take up only the force along ∇Cᵀ. They are held as a stiff penalty
  // ½ ρ_i (∇C_i (v + Δv) + C_i / h)², ρ_i ∇C_iᵀ ∇C_i joining segment i's block of the band,
  // with ρ_i = LENGTH_ROW_STIFFNESS · μ ℓ_i³. A yarn resting across a taut one under 10 g
  // (imex-contact, 5e-4 s, from the explicit step's rest at d = 0.915) drifts to d = 0.79
  // without the rows, 0.82 at 10⁴, 0.86 at 10⁶ and stays at 0.915 from 10⁸ (docs/model.md
  // §5.2); 10¹⁰ and 10¹² change nothing more.
  const int n_seg = m_model.num_seg();
  m_len_grad.resize(n_seg);
  m_len_c.resize(n_seg);
  m_len_rho.resize(n_seg);
  const double mu = m_model.params.material.density;
  static_assert(sizeof(Vector12d) == 12 * sizeof(double), "the gradients are stored back to back");
  if (n_seg > 0) length_constraints(m_model, s.q, {}, n_seg, m_len_c.data(), m_len_grad[0].data());
  tbb::parallel_for(tbb::blocked_range<int>(0, n_seg, 256), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i < r.end(); ++i) {
      const double l = m_model.rest_length[i];
      m_len_rho[i] = LENGTH_ROW_STIFFNESS * mu * l * l * l;
      m_blocks[i] += (m_len_rho[i] / (h * h)) * (m_len_grad[i] * m_len_grad[i].transpose());
    }
  });
}

void Simulator::solve_with_operator(const State& s, double h) {
  // (M + h² K_band + h² K_op) Δv = b on the free coordinates by conjugate gradients,
  // preconditioned with the factor of M + h² (K_band + the operators' segment parts);
  // m_dv starts as that factor's solution. Fixed coordinates keep their given Δv: the
  // residual and the search directions are zero there.
  const double h2 = h * h;
  const int n = static_cast<int>(m_dv.size());
  auto free_only = [&](Eigen::VectorXd& x) {
    for (int d : m_fixed_dofs) x[d] = 0;
  };
  auto apply = [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {  // y = A x
    band_product(x, h2, y);
    m_cg_kp.setZero(n);
    add_operator_product(x, m_cg_kp);
    y += h2 * m_cg_kp;
  };
  // the residual's scale: the right-hand side at the free coordinates without the length
  // rows' −ρ ∇C (∇C v + C / h). The band holds that term exactly, and it is large (ρ is a
  // stiff penalty: on the hanging 42×32's second step its norm is 2.6 × 10⁷, the rest's
  // 8.5); as the scale it made any residual small enough, and the solve stopped at the
  // factor's solution.
  Eigen::VectorXd& b = m_cg_z;
  b = m_rhs;
  for (size_t i = 0; i < m_len_c.size(); ++i) {
    const int base = 3 * m_model.seg_cp[i];
    const double rate = m_len_grad[i].dot(s.v.segment<12>(base)) + m_len_c[i] / h;
    b.segment<12>(base) += (m_len_rho[i] * rate) * m_len_grad[i];
  }
  free_only(b);
  const double b_norm = b.norm();
  m_cg_ap.resize(n);
  apply(m_dv, m_cg_ap);
  m_cg_r = m_rhs - m_cg_ap;
  free_only(m_cg_r);
  const double tol = m_model.params.solver.contact_solve_tolerance * std::max(b_norm, 1e-300);
  int iterations = 0;
  double r_norm = m_cg_r.norm();
  if (r_norm > tol) {
    m_stiff.solve(m_cg_r, m_cg_z);  // zero at the fixed coordinates, as r is
    m_cg_p = m_cg_z;
    double rz = m_cg_r.dot(m_cg_z);
    while (iterations < MAX_CG_ITERATIONS) {
      ++iterations;
      apply(m_cg_p, m_cg_ap);
      free_only(m_cg_ap);
      const double pap = m_cg_p.dot(m_cg_ap);
      if (!(pap > 0)) break;
      const double alpha = rz / pap;
      m_dv += alpha * m_cg_p;
      m_cg_r -= alpha * m_cg_ap;
      r_norm = m_cg_r.norm();
      if (r_norm <= tol) break;
      m_stiff.solve(m_cg_r, m_cg_z);
      const double rz_next = m_cg_r.dot(m_cg_z);
      m_cg_p = m_cg_z + (rz_next / rz) * m_cg_p;
      rz = rz_next;
    }
  }
  m_data.solve_iterations = iterations;
  m_data.solve_residual = b_norm > 0 ? r_norm / b_norm : 0.0;
}

void Simulator::build_solve_constraints() {
  if (m_solve_constraints_built) return;
  m_solve_constraints_built = true;
  m_mass3.resize(m_model.num_dof());
  for (int d = 0; d < m_model.num_dof(); ++d) m_mass3[d] = m_model.mass[d / 3];
  m_seg_ascending = true;
  for (int i = 1; i < m_model.num_seg() && m_seg_ascending; ++i)
    m_seg_ascending = m_model.seg_cp[i] > m_model.seg_cp[i - 1];
  // the clamps' control points: their new velocity is the clamp's, a given of the solve
  std::vector<char> fixed(m_model.num_dof(), 0);
  std::vector<int> owner(m_model.num_dof(), -1);
  const int groups = static_cast<int>(m_model.constraint_groups.size());
  for (int g = 0; g < groups; ++g)
    if (const auto* clamp = dynamic_cast<const ClampGroup*>(m_model.constraint_groups[g].get())) {
      const Clamp& c = clamp->clamp();
      for (size_t k = 0; k < c.control_points.size(); ++k) {
        m_clamped.push_back({clamp, static_cast<int>(c.points.size() + k), c.control_points[k]});
        for (int d = 0; d < 3; ++d) {
          fixed[3 * c.control_points[k] + d] = 1;
          owner[3 * c.control_points[k] + d] = g;
        }
      }
    }
  for (int d = 0; d < m_model.num_dof(); ++d)
    if (fixed[d]) {
      m_fixed_dofs.push_back(d);
      m_fixed_group.push_back(owner[d]);
    }
  // the segments that touch a clamped control point: the rows of the clamps' reaction
  for (int i = 0; i < m_model.num_seg(); ++i)
    for (int c = 0; c < 4; ++c)
      if (fixed[3 * (m_model.seg_cp[i] + c)]) {
        m_fixed_segments.push_back(i);
        break;
      }
  m_solve_force.assign(groups, Eigen::Vector3d::Zero());
  m_solve_torque.assign(groups, Eigen::Vector3d::Zero());
  // glues and pins (few rows, constant ∇C) as constraints of the solve; a row on fixed
  // coordinates alone is the clamp's (left out), and fixed coordinates leave every row
  int offset = 0;
  for (int g = 0; g < groups; ++g) {
    const ConstraintGroup* group = m_model.constraint_groups[g].get();
    const std::string_view kind = group->kind();
    if (kind != "glue" && kind != "pin") continue;
    m_solve_groups.push_back(group);
    std::vector<Eigen::Triplet<double>> entries;
    group->jacobian_structure(m_model, entries);
    std::vector<std::vector<std::pair<int, double>>> rows(group->rows());
    // duplicate entries (control points shared by both glued points) are summed
    for (const auto& e : entries) {
      auto& row = rows[e.row()];
      auto it =
          std::find_if(row.begin(), row.end(), [&](const auto& p) { return p.first == e.col(); });
      if (it == row.end())
        row.emplace_back(e.col(), e.value());
      else
        it->second += e.value();
    }
    for (int r = 0; r < group->rows(); ++r) {
      std::vector<std::pair<int, double>> free;
      for (const auto& entry : rows[r])
        if (!fixed[entry.first]) free.push_back(entry);
      if (free.empty()) continue;
      m_glue_rows.push_back(std::move(free));
      m_glue_rows_all.push_back(std::move(rows[r]));
      m_glue_row_of.push_back(offset + r);
      m_glue_row_group.push_back({g, r});
    }
    offset += group->rows();
  }
  m_glue_c.resize(offset);
}

template <class F>
double Simulator::glue_column_dot(int r, F&& value, int from, int to) const {
  // Σ_j W(j, r) value(j) over where column r of W is not 0 (and within [from, to))
  const int begin = std::max(m_glue_first[r], from), end = std::min(m_glue_end[r], to);
  double sum = 0;
  for (int j = begin; j < end; ++j) sum += m_glue_y(j, r) * value(j);
  return sum;
}

void Simulator::hold_glues_in_solve(const State& s, double h, Eigen::VectorXd& dv, bool kept,
                                    bool halfway) {
  const int m = static_cast<int>(m_glue_rows.size());
  if (m == 0) return;
  // with A = M + h² K = L Lᵀ: W = L⁻¹ Jᵀ (forward solves only, each from its column's
  // first entry), S = J A⁻¹ Jᵀ = Wᵀ W; J (v + Δv₀ − A⁻¹ Jᵀ μ) = −C(q, t + h) / h, and
  // A⁻¹ Jᵀ μ = L⁻ᵀ (W μ): one backward solve. Halfway (dv = y = L⁻¹ b, the solve's
  // forward half): J Δv₀ = J L⁻ᵀ y = Wᵀ y on the free coordinates, and the correction
  // y − W μ goes into the solve's own backward half. With the matrix kept (and J
  // constant: the glues' rows are built once), W and S are the last step's.
  const int n = static_cast<int>(dv.size());
  if (!kept || m_glue_y.rows() != n || m_glue_y.cols() != m) {
    m_glue_y.setZero(n, m);
    m_glue_first.assign(m, n);
    std::vector<int> last(m, 0);
    for (int r = 0; r < m; ++r)
      for (const auto& [dof, value] : m_glue_rows[r]) {
        m_glue_y(dof, r) = value;
        m_glue_first[r] = std::min(m_glue_first[r], dof);
        last[r] = std::max(last[r], dof);
      }
    // every column in one pass, each over the stretch of yarn where it has not died away
    // (below 10⁻²⁰ of its largest value: nothing a double sum of it can see)
    m_glue_end = m_stiff.forward_columns(m_glue_y, m_glue_first, last, 1e-20);
    Eigen::MatrixXd s(m, m);
    for (int a = 0; a < m; ++a)
      for (int b = 0; b <= a; ++b)
        s(a, b) = s(b, a) = glue_column_dot(
            a, [&](int j) { return m_glue_y(j, b); }, m_glue_first[b], m_glue_end[b]);
    m_glue_s.compute(s);
  }
  Eigen::VectorXd rhs(m);
  int offset = 0;
  for (const ConstraintGroup* group : m_solve_groups) {
    group->evaluate(m_model, s.q, s.time + h, m_glue_c.data() + offset, nullptr);
    offset += group->rows();
  }
  if (halfway)  // J Δv₀ on the free coordinates
    for (int r = 0; r < m; ++r) rhs[r] = glue_column_dot(r, [&](int j) { return dv[j]; });
  for (int r = 0; r < m; ++r) {
    // J v⁺ over every coordinate of the row: a fixed one's v⁺ is known (the solve gave
    // it its value, which y holds too), only the free ones' are corrected by A⁻¹ Jᵀ μ
    double jv = 0;
    for (const auto& [dof, value] : m_glue_rows_all[r]) jv += value * (s.v[dof] + dv[dof]);
    if (halfway) {
      for (const auto& [dof, value] : m_glue_rows[r]) jv -= value * dv[dof];
      jv += rhs[r];
    }
    rhs[r] = jv + m_glue_c[m_glue_row_of[r]] / h;
  }
  m_glue_mu = m_glue_s.solve(rhs);
  // W μ, each column over its own stretch
  auto subtract_w_mu = [&](Eigen::VectorXd& out) {
    for (int r = 0; r < m; ++r)
      for (int j = m_glue_first[r]; j < m_glue_end[r]; ++j) out[j] -= m_glue_y(j, r) * m_glue_mu[r];
  };
  if (halfway) {
    subtract_w_mu(dv);
    return;
  }
  Eigen::VectorXd column = Eigen::VectorXd::Zero(n);
  subtract_w_mu(column);
  m_stiff.backward(column);
  dv += column;
}

void Simulator::record_solve_forces(const Eigen::VectorXd& q, double time, double h) {
  for (auto& f : m_solve_force) f.setZero();
  for (auto& t : m_solve_torque) t.setZero();
  if (m_fixed_dofs.empty() && m_glue_rows.empty()) return;
  // each group's torque point, once per step (a clamp's comes from its keyframes)
  m_solve_about.resize(m_solve_force.size());
  for (size_t g = 0; g < m_solve_about.size(); ++g)
    m_solve_about[g] = m_model.constraint_groups[g]->torque_point(m_model, q, time);
  auto add = [&](int g, int dof, double f) {
    if (g < 0) return;
    Eigen::Vector3d force = Eigen::Vector3d::Zero();
    force[dof % 3] = f;
    m_solve_force[g] += force;
    m_solve_torque[g] += (q.segment<3>(dof - dof % 3) - m_solve_about[g]).cross(force);
  };
  // the clamps: what held their control points to the given velocities
  if (m_has_operator_terms) {
    // the factor's rows hold the preconditioner's blocks: A Δv − b from the terms instead,
    // on the rows of the segments that touch a clamped control point alone
    const double h2 = h * h;
    m_cg_kx.setZero(m_dv.size());
    for (int i : m_fixed_segments) {
      const int base = 3 * m_model.seg_cp[i];
      m_cg_kx.segment<12>(base) += m_blocks[i] * m_dv.segment<12>(base);
    }
    for (const auto& term : m_terms)
      if (term->has_operator_stiffness() && implicit(*term))
        term->add_stiffness_product_rows(m_model, m_dv, m_fixed_segments, m_cg_kx);
    m_fixed_residual.resize(m_fixed_dofs.size());
    for (size_t k = 0; k < m_fixed_dofs.size(); ++k) {
      const int d = m_fixed_dofs[k];
      m_fixed_residual[k] = m_model.mass[d / 3] * m_dv[d] + h2 * m_cg_kx[d] - m_b_fixed[k];
    }
  } else {
    m_stiff.fixed_residuals(m_dv, m_b_fixed, m_fixed_residual);
  }
  for (size_t k = 0; k < m_fixed_dofs.size(); ++k)
    add(m_fixed_group[k], m_fixed_dofs[k], m_fixed_residual[k] / h);
  // the glues and pins: −Jᵀ μ / h (a glue's record is the force on its point a, rows 0–2)
  for (size_t r = 0; r < m_glue_rows.size() && r < static_cast<size_t>(m_glue_mu.size()); ++r) {
    const auto [g, row] = m_glue_row_group[r];
    if (m_model.constraint_groups[g]->kind() == "glue") {
      if (row < 3) m_solve_force[g][row] -= m_glue_mu[r] / h;
      continue;
    }
    for (const auto& [dof, value] : m_glue_rows[r]) add(g, dof, -value * m_glue_mu[r] / h);
  }
}

ProjectionResult Simulator::project(Eigen::VectorXd& q, Eigen::VectorXd& v, double time, double h) {
  ScopedTimer timer(m_data.stage_seconds["projection"]);
  m_qpre = q;
  ProjectionResult res = m_projection.project(m_model, q, time);
  v += (q - m_qpre) / h;
  return res;
}

ProjectionResult Simulator::satisfy_constraints(State& state) {
  return m_projection.project(m_model, state.q, state.time);
}

void Simulator::apply_filters(const Eigen::VectorXd& q, Eigen::VectorXd& v, double time, double h) {
  for (auto& f : m_filters) {
    ScopedTimer timer(m_data.stage_seconds[std::string(f->name())]);
    f->apply(m_model, q, v, time, h);
  }
}

StepResult Simulator::step(State& state, double h) {
  StepResult res;
  const double t_new = state.time + h;
  if (is_imex(m_model.params.solver.integrator)) {
    if (!imex_step(state, h, m_qnew, m_vnew)) {
      res.status = StepStatus::NON_FINITE;
      res.message =
          "the implicit system M + h² K could not be factored at t = " + std::to_string(t_new) +
          " s; try a smaller time step";
      return res;
    }
  } else {
    unconstrained_step(state, h, m_qnew, m_vnew);
  }
  if (!m_qnew.allFinite() || !m_vnew.allFinite()) {
    res.status = StepStatus::NON_FINITE;
    res.message = "positions or velocities became non-finite in the unconstrained step at t = " +
                  std::to_string(t_new) + " s; try a smaller time step";
    return res;
  }
  res.projection = project(m_qnew, m_vnew, t_new, h);
  if (!res.projection.converged) {
    std::ostringstream msg;
    msg << "constraint projection did not converge at t = " << t_new
        << " s (max |C| = " << res.projection.max_violation << " after "
        << res.projection.iterations << " iterations); try a smaller time step";
    res.status = StepStatus::PROJECTION_FAILED;
    res.message = msg.str();
    return res;
  }
  // the filters see where the step started: the force records still describe it
  for (auto& f : m_filters) f->begin_step(m_data, state.q);
  apply_filters(m_qnew, m_vnew, t_new, h);
  bool moved = false;
  for (const auto& f : m_filters) moved = f->adjust_positions(m_model, m_qnew) || moved;
  // from here a failed step is thrown away after the filters saw it: they forget it
  auto reject = [&](std::string message, StepStatus status = StepStatus::NON_FINITE) {
    for (auto& f : m_filters) f->reject_step();
    res.status = status;
    res.message = std::move(message);
    return res;
  };
  if (!m_qnew.allFinite() || !m_vnew.allFinite())
    return reject("positions or velocities became non-finite at t = " + std::to_string(t_new) +
                  " s; try a smaller time step");
  // a step that moves a control point more than a yarn diameter relative to its
  // neighbour has torn the yarn's shape apart (two neighbours each moving a radius the
  // opposite way): the run is no longer trustworthy. Rigid motion, however fast, is not
  // instability.
  const double limit = 2 * m_model.params.material.radius;
  const Travel travel = step_travel(m_model, state.q, m_qnew);
  if (travel.relative > limit) {
    const int cp = travel.relative_cp;
    const int yarn = m_model.yarn_of_cp(cp);
    std::ostringstream msg;
    msg << "control point " << cp - m_model.yarns[yarn].cp_begin << " of yarn " << yarn << " moved "
        << travel.relative << " cm relative to its neighbour in one step at t = " << t_new
        << " s, more than the yarn diameter (" << limit
        << " cm): the run is unstable; try a smaller time step";
    return reject(msg.str());
  }
  if (m_model.params.solver.refuse_crossings) {
    ScopedTimer timer(m_data.stage_seconds["crossings"]);
    const std::vector<SegmentCrossing> crossed = find_crossings(m_model, state.q, m_qnew);
    if (!crossed.empty()) {
      const SegmentCrossing& c = crossed.front();
      std::ostringstream msg;
      msg << "yarns passed through each other in the step to t = " << t_new << " s: segment "
          << c.segment_a << " (yarn " << m_model.seg_yarn[c.segment_a] << ") and segment "
          << c.segment_b << " (yarn " << m_model.seg_yarn[c.segment_b] << ") at (" << c.point.x()
          << ", " << c.point.y() << ", " << c.point.z() << ") cm"
          << (crossed.size() > 1 ? " and " + std::to_string(crossed.size() - 1) + " more pairs"
                                 : std::string())
          << "; contact did not hold: try a smaller time step or --max-step-halvings";
      return reject(msg.str(), StepStatus::CROSSED);
    }
  }
  state.q.swap(m_qnew);
  state.v.swap(m_vnew);
  state.time = t_new;

  // step records: the projection and what each constraint group exerted
  ++m_data.steps;
  m_data.projection = {res.projection.converged, res.projection.iterations,
                       res.projection.max_violation};
  {
    ScopedTimer timer(m_data.stage_seconds["record"]);
    m_projection.record_groups(m_model, state.q, t_new, h, m_data.constraints);
    // with the IMEX step the solve held the clamps, pins and glues; the projection only
    // corrected what its linearisation left
    if (is_imex(m_model.params.solver.integrator) && m_solve_constraints_built)
      for (size_t g = 0; g < m_data.constraints.size() && g < m_solve_force.size(); ++g) {
        m_data.constraints[g].force += m_solve_force[g];
        m_data.constraints[g].torque += m_solve_torque[g];
      }
  }
  m_data.warnings.clear();
  const int max_it = m_model.params.solver.max_projection_iterations;
  if (res.projection.iterations > max_it / 2)
    m_data.warnings.push_back("the projection needed more than half its iterations (" +
                              std::to_string(res.projection.iterations) + " of " +
                              std::to_string(max_it) + ")");
  if (travel.absolute > m_model.params.material.radius && m_model.yarns.size() > 1)
    m_data.warnings.push_back("a yarn moved more than its radius in one step (" +
                              std::to_string(travel.absolute) +
                              " cm): contacts with other yarns can be missed");
  // the force records at the result (the next step's first evaluation); the projection
  // ended by evaluating C at exactly these positions and time, so max |C| is known
  // the projection ended by evaluating C at exactly these positions and time, unless a
  // filter moved them since
  forward(state, moved ? std::numeric_limits<double>::quiet_NaN() : res.projection.max_violation,
          m_lean);
  for (const auto& f : m_filters) f->record(m_data);
  if (m_data.contact.present && m_data.contact.min_distance_ratio < 0.5) {
    std::ostringstream msg;
    msg << "yarns came within half the contact distance (d = " << m_data.contact.min_distance_ratio
        << ")";
    m_data.warnings.push_back(msg.str());
  }
  return res;
}

double Simulator::force_residual(const State& state) {
  forward(state);  // (a no-op where data() already describes the state)
  m_data.static_constraints.clear();
  m_data.force_residual_peak = {};
  const int n = m_model.num_cp();
  Eigen::VectorXd zero = Eigen::VectorXd::Zero(state.q.size()), force;
  // exactly: no term reuses an earlier evaluation's model of its force here
  for (auto& term : m_terms) term->refresh();
  compute_forces(state.q, zero, state.time, force);
  // the acceleration a = M⁻¹ f, and the largest of its control points'
  Eigen::VectorXd a(force.size());
  double a_max = 0;
  for (int k = 0; k < n; ++k) {
    a.segment<3>(3 * k) = force.segment<3>(3 * k) / m_model.mass[k];
    a_max = std::max(a_max, a.segment<3>(3 * k).norm());
  }
  double residual = 0;
  if (a_max > 0) {
    // the projection's M⁻¹-orthogonal removal of what the constraints hold, applied to a
    // small displacement along a: (P(q₀ + ε a) − q₀) / ε, with q₀ = P(q) and ε moving the
    // most accelerated point by 1 % of the yarn radius (the projection's tolerance,
    // 1e-6 cm, is then 1e-3 of it)
    Eigen::VectorXd q0 = state.q;
    m_projection.project(m_model, q0, state.time);
    const double eps = 1e-2 * m_model.params.material.radius / a_max;
    Eigen::VectorXd q1 = q0 + eps * a;
    m_projection.project(m_model, q1, state.time, /*at_least_once=*/true);
    // its multipliers are the static reactions: a displacement ε M⁻¹ f is a step of
    // h = √ε from rest, whose constraint force −∇Cᵀ Λ / h² is then −(f along the normals)
    m_projection.record_groups(m_model, q1, state.time, std::sqrt(eps), m_data.static_constraints);
    double mass = 0;
    std::vector<double> share(n);  // m |a|² ε² per control point
    for (int k = 0; k < n; ++k) {
      share[k] = m_model.mass[k] * (q1.segment<3>(3 * k) - q0.segment<3>(3 * k)).squaredNorm();
      residual += share[k];
      mass += m_model.mass[k];
      const double peak = std::sqrt(share[k] / m_model.mass[k]) / eps;
      if (peak > m_data.force_residual_peak.acceleration) m_data.force_residual_peak = {k, peak, 0};
    }
    if (residual > 0) {
      const int top = std::max(1, n / 100);
      std::nth_element(share.begin(), share.begin() + (top - 1), share.end(), std::greater<>());
      double sum = 0;
      for (int k = 0; k < top; ++k) sum += share[k];
      m_data.force_residual_peak.top_share = sum / residual;
    }
    residual = mass > 0 ? std::sqrt(residual / mass) / eps : 0;
  }
  m_data.force_residual = residual;
  return residual;
}

double Simulator::kinetic_energy(const State& s) const {
  double e = 0;
  for (int k = 0; k < m_model.num_cp(); ++k)
    e += m_model.mass[k] * s.v.segment<3>(3 * k).squaredNorm();
  return 0.5 * e;
}

double Simulator::potential_energy(const State& s) {
  double e = 0;
  for (auto& term : m_terms) {
    term->refresh();
    e += term->energy(m_model, s.q, s.time);
  }
  return e;
}

Eigen::Vector3d Simulator::linear_momentum(const State& s) const {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < m_model.num_cp(); ++k) p += m_model.mass[k] * s.v.segment<3>(3 * k);
  return p;
}

Eigen::Vector3d Simulator::angular_momentum(const State& s) const {
  Eigen::Vector3d l = Eigen::Vector3d::Zero();
  for (int k = 0; k < m_model.num_cp(); ++k)
    l += m_model.mass[k] * s.q.segment<3>(3 * k).cross(s.v.segment<3>(3 * k));
  return l;
}

}  // namespace knit
