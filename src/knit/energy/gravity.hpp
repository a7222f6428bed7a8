#pragma once
// Gravity on the lumped masses: E = −Σ_k m_k g·q_k, force m_k g (dyn). g in cm/s².
#include "knit/energy/term.hpp"

namespace knit {

class Gravity final : public Term {
 public:
  std::string_view name() const override { return "gravity"; }
  double add_force(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                   double time, Eigen::VectorXd& force) override;
  double energy(const Model& model, const Eigen::VectorXd& q, double time) override;
  bool reads_velocity() const override { return false; }
};

}  // namespace knit
