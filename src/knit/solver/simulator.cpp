#include "knit/solver/simulator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "knit/contact/contact_term.hpp"
#include "knit/energy/bending.hpp"
#include "knit/energy/global_damping.hpp"
#include "knit/energy/gravity.hpp"
#include "knit/energy/length.hpp"

namespace knit {

namespace {

class ScopedTimer {
 public:
  explicit ScopedTimer(double& sink) : m_sink(sink), m_start(std::chrono::steady_clock::now()) {}
  ~ScopedTimer() {
    m_sink += std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
  }

 private:
  double& m_sink;
  std::chrono::steady_clock::time_point m_start;
};

// largest displacement of any control point between two position vectors (cm), and which
std::pair<double, int> max_travel(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  double worst = 0;
  int which = 0;
  for (Eigen::Index k = 0; k + 2 < a.size(); k += 3) {
    const double d = (a.segment<3>(k) - b.segment<3>(k)).squaredNorm();
    if (d > worst) {
      worst = d;
      which = static_cast<int>(k / 3);
    }
  }
  return {std::sqrt(worst), which};
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
  }
  return "unknown";
}

std::vector<std::unique_ptr<Term>> default_terms(const Model& model) {
  std::vector<std::unique_ptr<Term>> terms;
  terms.push_back(std::make_unique<Gravity>());
  terms.push_back(std::make_unique<BendingEnergy>());
  terms.push_back(std::make_unique<LengthEnergy>());
  if (model.params.k_global > 0) terms.push_back(std::make_unique<GlobalDamping>());
  if (model.params.contact) terms.push_back(std::make_unique<ContactTerm>(model));
  return terms;
}

Simulator::Simulator(Model model) : Simulator(model, default_terms(model)) {}

Simulator::Simulator(Model model, std::vector<std::unique_ptr<Term>> terms)
    : m_model(std::move(model)), m_terms(std::move(terms)), m_projection(m_model) {}

Term* Simulator::find_term(std::string_view name) const {
  for (const auto& t : m_terms)
    if (t->name() == name) return t.get();
  return nullptr;
}

double Simulator::compute_forces(const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                 Eigen::VectorXd& force) {
  force.setZero(q.size());
  double e = 0;
  for (auto& term : m_terms) {
    ScopedTimer timer(m_seconds[std::string(term->name())]);
    e += term->add_force(m_model, q, v, force);
  }
  return e;
}

void Simulator::unconstrained_step(const State& s, double h, Eigen::VectorXd& q_out,
                                   Eigen::VectorXd& v_out) {
  const Eigen::VectorXd& inv_m = m_model.inv_mass3;
  compute_forces(s.q, s.v, m_force);
  m_qmid = s.q + 0.5 * h * s.v;
  m_vmid = s.v + 0.5 * h * inv_m.cwiseProduct(m_force);
  compute_forces(m_qmid, m_vmid, m_force);
  q_out = s.q + h * m_vmid;
  v_out = s.v + h * inv_m.cwiseProduct(m_force);
}

ProjectionResult Simulator::project(Eigen::VectorXd& q, Eigen::VectorXd& v, double time, double h) {
  ScopedTimer timer(m_seconds["projection"]);
  m_qpre = q;
  ProjectionResult res = m_projection.project(m_model, q, time);
  v += (q - m_qpre) / h;
  return res;
}

ProjectionResult Simulator::satisfy_constraints(State& state) {
  return m_projection.project(m_model, state.q, state.time);
}

void Simulator::apply_filters(const Eigen::VectorXd& q, Eigen::VectorXd& v, double time) {
  for (auto& f : m_filters) {
    ScopedTimer timer(m_seconds[std::string(f->name())]);
    f->apply(m_model, q, v, time);
  }
}

StepResult Simulator::step(State& state, double h) {
  StepResult res;
  unconstrained_step(state, h, m_qnew, m_vnew);
  const double t_new = state.time + h;
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
  apply_filters(m_qnew, m_vnew, t_new);
  if (!m_qnew.allFinite() || !m_vnew.allFinite()) {
    res.status = StepStatus::NON_FINITE;
    res.message = "positions or velocities became non-finite at t = " + std::to_string(t_new) +
                  " s; try a smaller time step";
    return res;
  }
  // a control point that moves more than a yarn radius in one step can carry its yarn
  // through another one between two contact evaluations: the run is no longer trustworthy
  const auto [travel, cp] = max_travel(state.q, m_qnew);
  if (travel > m_model.params.radius) {
    int yarn = 0;
    while (cp >= m_model.yarns[yarn].cp_end) ++yarn;
    std::ostringstream msg;
    msg << "control point " << cp - m_model.yarns[yarn].cp_begin << " of yarn " << yarn << " moved "
        << travel << " cm in one step at t = " << t_new << " s, more than the yarn radius ("
        << m_model.params.radius << " cm): the run is unstable; try a smaller time step";
    res.status = StepStatus::NON_FINITE;
    res.message = msg.str();
    return res;
  }
  state.q.swap(m_qnew);
  state.v.swap(m_vnew);
  state.time = t_new;
  return res;
}

double Simulator::kinetic_energy(const State& s) const {
  double e = 0;
  for (int k = 0; k < m_model.num_cp(); ++k)
    e += m_model.mass[k] * s.v.segment<3>(3 * k).squaredNorm();
  return 0.5 * e;
}

double Simulator::potential_energy(const State& s) {
  double e = 0;
  for (auto& term : m_terms) e += term->energy(m_model, s.q);
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
